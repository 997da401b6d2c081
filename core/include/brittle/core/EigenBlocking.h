// EigenBlocking.h — dense products summed in the same order on every CPU.
//
// Eigen's matrix-matrix products split their inner dimension into blocks sized from the CPU's
// cache sizes, which it reads with cpuid the first time a product asks. A product summed in other
// blocks rounds otherwise, so the same pack and impact gave other bits on a machine with other
// caches: the main job's plate impact had one fingerprint with a 48 KB / 2 MB / 260 MB Xeon's
// sizes and another with 32 KB / 512 KB / 16 MB, and the pinned fingerprints then held on one
// kind of machine only. So, twice over:
// - every target of the project compiles with EIGEN_NO_CPUID and these sizes as Eigen's defaults
//   (cmake/BrittleTargets.cmake): no copy of Eigen's setting in the project asks the CPU. (A library
//   may hold its own copy: brittle_precompute's is local to it, the others share one process-wide.)
// - each entry point that computes (World::create, the object and database bakes, the CLI) sets
//   them again before its first product, so that a host's Eigen::setCpuCacheSizes, or a host built
//   without the definition whose Eigen asked the CPU first, changes no bits either.
// The sizes are Eigen's own x86-64 defaults. They change how fast large products run, never what
// they compute beyond their rounding.
#pragma once

#include <Eigen/Core>
#include <cstddef>

namespace brittle {

inline constexpr std::ptrdiff_t kEigenBlockingL1 = 32 * 1024;
inline constexpr std::ptrdiff_t kEigenBlockingL2 = 256 * 1024;
inline constexpr std::ptrdiff_t kEigenBlockingL3 = 2 * 1024 * 1024;

/// Sets Eigen's product blocking to the fixed cache sizes above (see the file comment). Cheap;
/// call it before computing, from the thread that then starts the work.
inline void pinEigenBlocking() { Eigen::setCpuCacheSizes(kEigenBlockingL1, kEigenBlockingL2, kEigenBlockingL3); }

}  // namespace brittle
