#pragma once
// tinygltf as shadowlab builds it (gltf_tinygltf.cpp holds its implementation): without stb_image
// (images stay encoded bytes until a MASK material needs one, decoded through image_io.h), without
// image writing and without reading external images at load time. Every file that includes
// tiny_gltf.h includes it through here, so the class layout and its default callbacks agree.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>
