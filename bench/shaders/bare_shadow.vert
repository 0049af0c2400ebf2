#version 460
// The bare yardstick's shadow pass (bench/raster_bare_bench.cpp): position only, depth only.
layout(location = 0) in vec3 inPosition;
layout(push_constant) uniform Push { mat4 clip; mat4 lightTex; } pc;
void main() { gl_Position = pc.clip * vec4(inPosition, 1.0); }
