// Hot loops are compiled twice, for x86-64-v3 (AVX2) and the baseline, the version picked when
// the program loads. The library is built with -ffp-contract=off (no fused multiply-adds), so
// both versions give the same bits. meson's -Dvector_clones=false builds the baseline only.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(PYROCAM_NO_VECTOR_CLONES)
#define PYROCAM_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define PYROCAM_VECTOR_CLONES
#endif

namespace pyrocam {

// Four doubles that the compiler keeps in one AVX register (two SSE ones in the baseline
// version), for kernels that spell out their lanes. Read from any double (aligned(8),
// may_alias); passed by reference only (by value the baseline's ABI differs).
typedef double Lanes __attribute__((vector_size(32), aligned(8), may_alias));

}  // namespace pyrocam
