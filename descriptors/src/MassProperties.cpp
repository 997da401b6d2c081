#include "brittle/descriptors/MassProperties.h"

namespace brittle {
namespace {

// From ∫1, ∫x, ∫xxᵀ about an origin: the properties about the centre of mass.
MassProperties finishMassProperties(double volume, const Eigen::Vector3d& first, const Eigen::Matrix3d& second,
                                    const Eigen::Vector3d& origin, double density) {
  MassProperties out;
  out.volumeM3 = volume;
  out.massKg = density * volume;
  if (volume == 0.0) return out;
  const Eigen::Vector3d cLocal = first / volume;
  out.centerOfMassM = cLocal + origin;
  out.secondMomentM5 = second - volume * cLocal * cLocal.transpose();
  const Eigen::Matrix3d c = density * out.secondMomentM5;
  out.inertiaKgM2 = c.trace() * Eigen::Matrix3d::Identity() - c;
  return out;
}

// Accumulates ∫1, ∫x, ∫xxᵀ over signed tetrahedra, relative to an origin that keeps the numbers
// small (cancellation would otherwise cost digits on meshes far from the world origin).
class MomentAccumulator {
 public:
  explicit MomentAccumulator(const Eigen::Vector3d& origin) : mOrigin(origin) {}

  void addTet(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
              const Eigen::Vector3d& d) {
    const Eigen::Vector3d p0 = a - mOrigin, p1 = b - mOrigin, p2 = c - mOrigin, p3 = d - mOrigin;
    const double v = signedTetVolume(p0, p1, p2, p3);
    const Eigen::Vector3d s = p0 + p1 + p2 + p3;
    mVolume += v;
    mFirst += v * s / 4.0;
    mSecond += v / 20.0 *
               (p0 * p0.transpose() + p1 * p1.transpose() + p2 * p2.transpose() +
                p3 * p3.transpose() + s * s.transpose());
  }

  MassProperties finish(double density) const { return finishMassProperties(mVolume, mFirst, mSecond, mOrigin, density); }

 private:
  Eigen::Vector3d mOrigin;
  double mVolume = 0.0;
  Eigen::Vector3d mFirst = Eigen::Vector3d::Zero();
  Eigen::Matrix3d mSecond = Eigen::Matrix3d::Zero();
};

Eigen::Vector3d boxCenter(const Points& points) {
  if (points.rows() == 0) return Eigen::Vector3d::Zero();
  return 0.5 * (points.colwise().minCoeff() + points.colwise().maxCoeff()).transpose();
}

}  // namespace

MassProperties computeSurfaceMassProperties(const TriangleMesh& surface, double densityKgPerM3) {
  const Eigen::Vector3d origin = boxCenter(surface.vertices);
  MomentAccumulator acc(origin);
  for (Eigen::Index f = 0; f < surface.faces.rows(); ++f) {
    acc.addTet(origin, surface.vertices.row(surface.faces(f, 0)).transpose(),
               surface.vertices.row(surface.faces(f, 1)).transpose(),
               surface.vertices.row(surface.faces(f, 2)).transpose());
  }
  return acc.finish(densityKgPerM3);
}

MassProperties massPropertiesFromMoments(const double* v, const Eigen::Vector3d& originM, double densityKgPerM3) {
  // Graded order: 1, x, y, z, xx, xy, xz, yy, yz, zz.
  Eigen::Matrix3d second;
  second << v[4], v[5], v[6], v[5], v[7], v[8], v[6], v[8], v[9];
  return finishMassProperties(v[0], Eigen::Vector3d(v[1], v[2], v[3]), second, originM, densityKgPerM3);
}

MassProperties massPropertiesFromMoments(const VolumeMoments& m, const Eigen::Vector3d& originM, double densityKgPerM3) {
  return massPropertiesFromMoments(m.values.data(), originM, densityKgPerM3);
}

MassProperties computeTetMassProperties(const TetMesh& mesh, double densityKgPerM3) {
  MomentAccumulator acc(boxCenter(mesh.nodes));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    acc.addTet(mesh.nodes.row(mesh.tets(t, 0)).transpose(), mesh.nodes.row(mesh.tets(t, 1)).transpose(),
               mesh.nodes.row(mesh.tets(t, 2)).transpose(), mesh.nodes.row(mesh.tets(t, 3)).transpose());
  }
  return acc.finish(densityKgPerM3);
}

}  // namespace brittle
