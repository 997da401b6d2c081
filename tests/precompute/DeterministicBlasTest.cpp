// The BLAS that ARPACK, CHOLMOD and Ceres call gives the same bits wherever its operands lie.
// ATLAS, which Debian prefers once libceres is installed, does not: its dnrm2 rounds differently
// at some alignments, which made ARPACK's Ritz vectors, and so baked packs, depend on where the
// heap put a buffer. The build links the reference BLAS and LAPACK first (CMakeLists.txt); this
// test takes dnrm2 and ddot as brittle_precompute's dependencies see them (the process's global
// symbol scope), calls them on the same vectors at every 8-byte offset within a 64-byte line, and
// asks for one answer. (With ATLAS preloaded, LD_PRELOAD=…/atlas/libblas.so.3, it fails.)
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace brittle {
namespace {

using Nrm2 = double (*)(const int*, const double*, const int*);
using Dot = double (*)(const int*, const double*, const int*, const double*, const int*);

TEST(DeterministicBlas, SameBitsAtEveryAlignment) {
  const auto dnrm2_ = reinterpret_cast<Nrm2>(dlsym(RTLD_DEFAULT, "dnrm2_"));
  const auto ddot_ = reinterpret_cast<Dot>(dlsym(RTLD_DEFAULT, "ddot_"));
  ASSERT_NE(dnrm2_, nullptr) << "no BLAS loaded with brittle_precompute";
  ASSERT_NE(ddot_, nullptr);
  Dl_info where{};
  ASSERT_NE(dladdr(reinterpret_cast<void*>(dnrm2_), &where), 0);
  EXPECT_EQ(std::string(where.dli_fname).find("atlas"), std::string::npos) << where.dli_fname;
  // ATLAS's dnrm2 gives another last bit on about one unit vector in 5 000 of mixed-scale entries
  // (measured: 12 of 59 600 vectors, lengths 2–299, when the vector moves within a 64-byte line),
  // so the test draws that many.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> value(-0.5, 0.5);
  std::vector<double> x(300), y(300), bx(316), by(316);
  auto aligned = [](std::vector<double>& b) {
    const auto a = reinterpret_cast<std::uintptr_t>(b.data());
    return b.data() + ((64 - a % 64) % 64) / sizeof(double);
  };
  double* ax = aligned(bx);
  double* ay = aligned(by);
  const int one = 1;
  int differing = 0;
  for (int n = 2; n < 300; ++n) {
    for (int trial = 0; trial < 200; ++trial) {
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        x[static_cast<size_t>(i)] = value(rng) * std::ldexp(1.0, static_cast<int>(rng() % 3));
        y[static_cast<size_t>(i)] = value(rng);
        sum += x[static_cast<size_t>(i)] * x[static_cast<size_t>(i)];
      }
      for (int i = 0; i < n; ++i) x[static_cast<size_t>(i)] /= std::sqrt(sum);
      double nrm0 = 0.0, dot0 = 0.0;
      bool differs = false;
      for (int offset = 0; offset < 8; ++offset) {
        std::memcpy(ax + offset, x.data(), sizeof(double) * static_cast<size_t>(n));
        std::memcpy(ay + offset, y.data(), sizeof(double) * static_cast<size_t>(n));
        const double nrm = dnrm2_(&n, ax + offset, &one), dot = ddot_(&n, ax + offset, &one, ay + offset, &one);
        if (offset == 0) {
          nrm0 = nrm;
          dot0 = dot;
        }
        differs = differs || nrm != nrm0 || dot != dot0;
      }
      differing += differs;
    }
  }
  EXPECT_EQ(differing, 0) << "BLAS results that depend on the operands' alignment";
}

}  // namespace
}  // namespace brittle
