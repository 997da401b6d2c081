// DescriptorTypes.h — the array types shared by the shape descriptors.
//
// Descriptors are float32: they feed nearest-neighbour indices (FLANN) and HDF5 matrices, where
// half the memory matters more than the digits beyond ~1e-7 relative.
#pragma once

#include <Eigen/Core>

namespace brittle {

using Descriptor = Eigen::VectorXf;  ///< D values
/// #candidates (or #entries) by D, row-major so each descriptor is one contiguous row.
using DescriptorMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Euclidean distance between two descriptors of the same kind and size.
inline float descriptorL2Distance(const Descriptor& a, const Descriptor& b) { return (a - b).norm(); }

}  // namespace brittle
