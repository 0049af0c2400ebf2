#version 460
// One comparison lookup (the sampler's filter: NEAREST for none, LINEAR for hw2x2) with a
// constant bias, written as a grey level: what a single-purpose shadow-mapping program does.
layout(set = 0, binding = 0) uniform sampler2DShadow shadowMap;
layout(location = 0) in vec4 lightCoord;
layout(location = 0) out vec4 color;
void main() {
  float vis = textureProj(shadowMap, vec4(lightCoord.xy, lightCoord.z - 0.0005 * lightCoord.w, lightCoord.w));
  color = vec4(vec3(vis), 1.0);
}
