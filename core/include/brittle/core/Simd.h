// Simd.h — 256-bit vector lanes where the CPU has them, with the bits of the 128-bit ones.
//
// A few hot loops are written with GCC vector types: two doubles or four floats to an SSE2
// register, which every x86-64 CPU has. Each also comes in a 256-bit (AVX) form, chosen at run
// time. Every lane takes the same IEEE operations in the same order in both forms, and neither
// contracts a product and a sum into a fused multiply-add (AVX has none; FMA is a separate
// extension that no target here enables). So the results are the same bits on a CPU with AVX and
// on one without: fractures and packs stay bit-identical across machines. Tests run both forms.
//
// A function marked BRITTLE_TARGET_AVX calls nothing while its 256-bit registers are live (inline
// what it needs), so that GCC clears their upper halves on return (vzeroupper). Calling SSE2 code
// with them live made every later stage of an impact slower, the untouched ones included.
#pragma once

#include <cstdlib>
#include <cstring>

namespace brittle {

/// Which registers a vectorised loop uses.
enum class Lanes {
  Narrow,  ///< 128-bit (SSE2): every x86-64 CPU
  Wide,    ///< 256-bit (AVX), where the CPU has it
};

/// The widest lanes this CPU runs. The environment variable BRITTLE_SIMD=sse2 keeps a process to the
/// 128-bit forms, as on a CPU without AVX: the determinism check runs one of its three processes so
/// and requires the same packs and fractures from it.
inline Lanes widestLanes() {
#if defined(__x86_64__) || defined(__i386__)
  static const Lanes lanes = [] {
    const char* forced = std::getenv("BRITTLE_SIMD");
    if (forced && std::strcmp(forced, "sse2") == 0) return Lanes::Narrow;
    return __builtin_cpu_supports("avx") ? Lanes::Wide : Lanes::Narrow;
  }();
  return lanes;
#else
  return Lanes::Narrow;
#endif
}

/// L values of T to one register, as a GCC vector type: VectorOf<double, 2> and VectorOf<float, 4>
/// fill an SSE2 register, VectorOf<double, 4> and VectorOf<float, 8> an AVX one. (GCC takes a
/// dependent vector_size in a class template's typedef, not in an alias template.)
template <class T, int L>
struct SimdPack {
  typedef T type __attribute__((vector_size(L * sizeof(T))));
  typedef T unaligned __attribute__((vector_size(L * sizeof(T)), aligned(alignof(T)), may_alias));
};
template <class T, int L>
using VectorOf = typename SimdPack<T, L>::type;

/// v ← L values from p, which need only T's alignment: one unaligned load. (Not a memcpy: GCC's
/// generic tuning copies 32 bytes as two 16-byte halves through the stack. An output argument,
/// not a return value: a 256-bit return type changes the ABI where AVX is not enabled.)
template <int L, class T>
[[gnu::always_inline]] inline void loadLanes(const T* p, VectorOf<T, L>& v) {
  v = *reinterpret_cast<const typename SimdPack<T, L>::unaligned*>(p);
}

/// Asks the cache for the bytes [begin, end) ahead of their reads, a 64-byte line at a time (a
/// hint: no effect on any value). Inlined, so an AVX function may use it with its registers live.
[[gnu::always_inline]] inline void prefetchBytes(const void* begin, const void* end) {
  for (const char* p = static_cast<const char*>(begin); p < static_cast<const char*>(end); p += 64) __builtin_prefetch(p);
}

}  // namespace brittle

/// Marks a function compiled for AVX (no FMA), called only where widestLanes() is Wide.
#if defined(__x86_64__) || defined(__i386__)
#define BRITTLE_TARGET_AVX __attribute__((target("avx")))
#else
#define BRITTLE_TARGET_AVX
#endif
