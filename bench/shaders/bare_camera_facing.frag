#version 460
// bare_camera.frag's one comparison lookup, unlit where the light is behind the visible side
// (shadowlab's facing rule, the N.L = 0 of a shading program): the camera and the light see the
// triangle from the same side exactly where its map coordinates keep their orientation across the
// screen, a positive Jacobian determinant of (u, v) over the pixel's (x, y) (both y downwards).
layout(set = 0, binding = 0) uniform sampler2DShadow shadowMap;
layout(location = 0) in vec4 lightCoord;
layout(location = 0) out vec4 color;
void main() {
  float vis = textureProj(shadowMap, vec4(lightCoord.xy, lightCoord.z - 0.0005 * lightCoord.w, lightCoord.w));
  vec2 uv = lightCoord.xy / lightCoord.w, du = dFdx(uv), dv = dFdy(uv);
  if (!(du.x * dv.y - du.y * dv.x > 0.0)) vis = 0.0;
  color = vec4(vec3(vis), 1.0);
}
