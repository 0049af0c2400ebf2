#version 460
// Depth only: no color attachment, nothing to write.
void main() {}
