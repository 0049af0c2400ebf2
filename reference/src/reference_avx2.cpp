// The trace (reference.cpp) compiled a second time for AVX2, as
// reference_detail::renderReferenceAvx2; renderReference calls it where the CPU has AVX2
// (ReferenceOptions::simd). CMake gives this file -mavx2 -mno-fma -ffp-contract=off, so every
// operation stays the baseline's IEEE operation in the same order (no fused multiply-add): the same
// bits, with 8 floats (4 doubles) per register instead of 4 (2). And -fno-weak: the inline functions
// and template instantiations compiled here stay local to this object instead of being weak
// definitions the linker could pick for other objects' calls, which would then run AVX2 code on a
// CPU without it. Only renderReferenceAvx2 is global here.
#ifdef SHADOWLAB_REFERENCE_HAS_AVX2
#define SHADOWLAB_REFERENCE_AVX2_TU 1
#include "reference.cpp"
#endif
