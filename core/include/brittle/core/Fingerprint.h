// Fingerprint.h — 64-bit fingerprints of computed values, for bit-identity checks (replays,
// determinism across processes and thread counts, pinned golden values in the tests, a built
// search index's digest).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace brittle {

/// FNV-1a (64 bits) over the bytes of the values added, in the order added. Equal inputs, bit for
/// bit, give equal fingerprints; it is not a cryptographic hash.
class Fingerprint {
 public:
  void addBytes(const void* data, size_t count) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < count; ++i) mHash = (mHash ^ p[i]) * 1099511628211ull;
  }
  template <typename T>
    requires std::is_arithmetic_v<T>
  void add(T value) {
    addBytes(&value, sizeof value);
  }
  void add(const std::string& text) {
    add(static_cast<uint64_t>(text.size()));
    addBytes(text.data(), text.size());
  }
  /// The shape, then the coefficients row by row (the same for either storage order).
  template <typename Derived>
  void add(const Eigen::DenseBase<Derived>& m) {
    add(static_cast<int64_t>(m.rows()));
    add(static_cast<int64_t>(m.cols()));
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      for (Eigen::Index j = 0; j < m.cols(); ++j) add(m(i, j));
    }
  }
  /// A vector's length, then its values' bytes.
  template <typename T>
    requires std::is_arithmetic_v<T>
  void add(const std::vector<T>& values) {
    add(static_cast<uint64_t>(values.size()));
    addBytes(values.data(), sizeof(T) * values.size());
  }
  /// Several values, in order.
  template <typename... T>
    requires(sizeof...(T) > 1)
  void add(const T&... values) {
    (add(values), ...);
  }
  uint64_t value() const { return mHash; }

 private:
  uint64_t mHash = 1469598103934665603ull;
};

}  // namespace brittle
