#version 460
// The bare program's pcf (filter=pcf, filter.size 3, raster/METHODS.md): the mean of the 3 x 3
// comparisons around the texel under the lookup, with the constant comparison bias, as four 2x2
// comparison gathers (one call for four texels' comparisons; the right column and bottom row of
// gathers use half their texels), written as a grey level. The same taps and decisions as
// shadowlab's kFilterPcf (resolve.frag), written as a single-purpose program would; unlit where
// the light is behind the visible side (bare_camera_facing.frag).
layout(set = 0, binding = 0) uniform sampler2DShadow shadowMap;
layout(location = 0) in vec4 lightCoord;
layout(location = 0) out vec4 color;
void main() {
  vec3 p = lightCoord.xyz / lightCoord.w;
  float ref = p.z - 0.0005;
  float size = float(textureSize(shadowMap, 0).x);
  vec2 c = floor(p.xy * size);
  // A gather at texel corner (t + 1) / size returns the comparisons of texels t .. t + 1:
  // w (t.x, t.y), z (t.x + 1, t.y), x (t.x, t.y + 1), y (t.x + 1, t.y + 1).
  vec4 a = textureGather(shadowMap, c / size, ref);                     // texels c - 1 .. c
  vec4 b = textureGather(shadowMap, (c + vec2(2.0, 0.0)) / size, ref);  // column c + 1, rows c - 1 .. c
  vec4 d = textureGather(shadowMap, (c + vec2(0.0, 2.0)) / size, ref);  // row c + 1, columns c - 1 .. c
  float e = textureGather(shadowMap, (c + vec2(2.0)) / size, ref).w;    // texel (c + 1, c + 1)
  float vis = (a.x + a.y + a.z + a.w + b.w + b.x + d.w + d.z + e) / 9.0;
  vec2 du = dFdx(p.xy), dv = dFdy(p.xy);
  if (!(du.x * dv.y - du.y * dv.x > 0.0)) vis = 0.0;
  color = vec4(vec3(vis), 1.0);
}
