#version 460
// The bare yardstick's camera pass: clip position and the point's light texture coordinates.
layout(location = 0) in vec3 inPosition;
layout(push_constant) uniform Push { mat4 clip; mat4 lightTex; } pc;
layout(location = 0) out vec4 lightCoord;
void main() {
  gl_Position = pc.clip * vec4(inPosition, 1.0);
  lightCoord = pc.lightTex * vec4(inPosition, 1.0);
}
