// Renderer.cpp — the OpenGL 2.1 drawing of Renderer.h.
#include "brittle/viewer/Renderer.h"

#include <GL/gl.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brittle/precompute/BaseShapes.h"

namespace brittle {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::array<float, 3> colourOf(BodyKind kind) {
  switch (kind) {
    case BodyKind::Object: return {0.55f, 0.68f, 0.85f};
    case BodyKind::Fragment: return {0.35f, 0.78f, 0.72f};
    case BodyKind::Debris: return {0.86f, 0.74f, 0.50f};
    case BodyKind::Impactor: return {0.78f, 0.78f, 0.82f};
  }
  return {1.0f, 1.0f, 1.0f};
}

// A column-major 4 × 4 matrix for glLoadMatrixd / glMultMatrixd.
std::array<double, 16> toGl(const Eigen::Matrix4d& m) {
  std::array<double, 16> a{};
  Eigen::Map<Eigen::Matrix4d>(a.data()) = m;
  return a;
}

Eigen::Matrix4d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d f = (target - eye).normalized();
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4d perspective(double fovYDeg, double aspect, double nearM, double farM) {
  const double f = 1.0 / std::tan(0.5 * fovYDeg * kDeg);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (farM + nearM) / (nearM - farM);
  m(2, 3) = 2.0 * farM * nearM / (nearM - farM);
  m(3, 2) = -1.0;
  return m;
}

}  // namespace

Eigen::Vector3d OrbitCamera::eye() const {
  const double yaw = yawDeg * kDeg, pitch = pitchDeg * kDeg;
  return target + distanceM * Eigen::Vector3d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch));
}

OrbitCamera OrbitCamera::framing(const std::vector<BodyView>& bodies, std::optional<double> floorHeightM) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const BodyView& b : bodies) {
    if (b.surface) {
      for (Eigen::Index v = 0; v < b.surface->vertices.rows(); ++v) {
        const Eigen::Vector3d x = b.rotation * b.surface->vertices.row(v).transpose() + b.translationM;
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
      }
    } else {
      lo = lo.cwiseMin(b.translationM);
      hi = hi.cwiseMax(b.translationM);
    }
  }
  OrbitCamera c;
  if (!(lo.array() <= hi.array()).all()) return c;
  if (floorHeightM) lo.z() = std::min(lo.z(), *floorHeightM);
  c.target = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 0.05);
  c.distanceM = 1.1 * radius / std::sin(0.5 * c.fovYDeg * kDeg);
  return c;
}

void OrbitCamera::ray(double x, double y, int width, int height, Eigen::Vector3d& origin, Eigen::Vector3d& direction) const {
  const Eigen::Vector3d e = eye();
  const Eigen::Vector3d f = (target - e).normalized();
  const Eigen::Vector3d s = f.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d u = s.cross(f);
  const double t = std::tan(0.5 * fovYDeg * kDeg), aspect = static_cast<double>(width) / std::max(height, 1);
  const double nx = 2.0 * (x + 0.5) / width - 1.0, ny = 1.0 - 2.0 * (y + 0.5) / height;
  origin = e;
  direction = (f + nx * t * aspect * s + ny * t * u).normalized();
}

const Renderer::Mesh& Renderer::meshFor(const BodyView& body) {
  auto [it, inserted] = mMeshes.try_emplace(body.index);
  if (!inserted) return it->second;
  TriangleMesh shape;
  if (body.surface) {
    shape = *body.surface;
  } else if (body.impactor) {
    BaseShapeDefinition d;
    d.name = "impactor";
    if (body.impactor->shape == ImpactorShape::Sphere) {
      d.kind = BaseShapeKind::Sphere;
      d.sizeM = Eigen::Vector3d::Constant(2.0 * body.impactor->radiusM);
    } else {
      d.kind = BaseShapeKind::Box;
      d.sizeM = 2.0 * body.impactor->halfExtentsM;
    }
    if (auto made = makeBaseShape(d)) shape = std::move(made).value();
  }
  Mesh& m = it->second;
  for (Eigen::Index f = 0; f < shape.faces.rows(); ++f) {
    const Eigen::Vector3d a = shape.vertices.row(shape.faces(f, 0)), b = shape.vertices.row(shape.faces(f, 1)),
                          c = shape.vertices.row(shape.faces(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() > 0.0) n.normalize();
    for (const Eigen::Vector3d* p : {&a, &b, &c}) {
      for (int k = 0; k < 3; ++k) {
        m.positions.push_back(static_cast<float>((*p)[k]));
        m.normals.push_back(static_cast<float>(n[k]));
      }
    }
  }
  return m;
}

void Renderer::draw(const std::vector<BodyView>& bodies, const OrbitCamera& camera, std::optional<double> floorHeightM,
                    int width, int height) {
  glViewport(0, 0, width, height);
  glClearColor(0.13f, 0.14f, 0.17f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);  // fragment surfaces are closed, but a camera inside one should see it
  glMatrixMode(GL_PROJECTION);
  const double far = 20.0 * camera.distanceM, near = std::max(1e-3, 0.01 * camera.distanceM);
  const auto projection = toGl(perspective(camera.fovYDeg, static_cast<double>(width) / std::max(height, 1), near, far));
  glLoadMatrixd(projection.data());
  glMatrixMode(GL_MODELVIEW);
  const auto view = toGl(lookAt(camera.eye(), camera.target, Eigen::Vector3d::UnitZ()));
  glLoadMatrixd(view.data());

  // A light from above and behind the camera, in world coordinates.
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glEnable(GL_NORMALIZE);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  const Eigen::Vector3d light = (camera.eye() - camera.target).normalized() + Eigen::Vector3d(0.3, -0.2, 1.0);
  const float position[4] = {static_cast<float>(light.x()), static_cast<float>(light.y()), static_cast<float>(light.z()), 0.0f};
  const float ambient[4] = {0.25f, 0.25f, 0.28f, 1.0f}, diffuse[4] = {0.85f, 0.85f, 0.85f, 1.0f};
  glLightfv(GL_LIGHT0, GL_POSITION, position);
  glLightfv(GL_LIGHT0, GL_AMBIENT, ambient);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);

  if (floorHeightM) {
    const double half = 2.0 * camera.distanceM, cell = std::pow(10.0, std::floor(std::log10(half / 5.0)));
    const int n = static_cast<int>(std::ceil(half / cell));
    // Cells on a fixed lattice (they do not move with the camera), colours by lattice parity.
    const auto i0 = static_cast<int64_t>(std::floor(camera.target.x() / cell)), j0 = static_cast<int64_t>(std::floor(camera.target.y() / cell));
    glNormal3d(0.0, 0.0, 1.0);
    glBegin(GL_QUADS);
    for (int64_t i = i0 - n; i < i0 + n; ++i)
      for (int64_t j = j0 - n; j < j0 + n; ++j) {
        const float g = ((i + j) & 1) ? 0.30f : 0.36f;
        glColor3f(g, g, g + 0.02f);
        const double xs = static_cast<double>(i) * cell, ys = static_cast<double>(j) * cell;
        glVertex3d(xs, ys, *floorHeightM);
        glVertex3d(xs + cell, ys, *floorHeightM);
        glVertex3d(xs + cell, ys + cell, *floorHeightM);
        glVertex3d(xs, ys + cell, *floorHeightM);
      }
    glEnd();
  }

  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  for (const BodyView& b : bodies) {
    const Mesh& m = meshFor(b);
    if (m.positions.empty()) continue;
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
    pose.block<3, 3>(0, 0) = b.rotation;
    pose.block<3, 1>(0, 3) = b.translationM;
    const auto model = toGl(pose);
    glPushMatrix();
    glMultMatrixd(model.data());
    const auto colour = colourOf(b.kind);
    glColor3f(colour[0], colour[1], colour[2]);
    glVertexPointer(3, GL_FLOAT, 0, m.positions.data());
    glNormalPointer(GL_FLOAT, 0, m.normals.data());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(m.positions.size() / 3));
    glPopMatrix();
  }
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
  glDisable(GL_LIGHTING);
}

std::vector<uint8_t> Renderer::readPixels(int width, int height) const {
  std::vector<uint8_t> rgba(static_cast<size_t>(width) * static_cast<size_t>(height) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  // GL's first row is the bottom one.
  const size_t stride = static_cast<size_t>(width) * 4;
  for (int y = 0; y < height / 2; ++y) {
    std::swap_ranges(rgba.begin() + static_cast<std::ptrdiff_t>(y * stride), rgba.begin() + static_cast<std::ptrdiff_t>((y + 1) * stride),
                     rgba.begin() + static_cast<std::ptrdiff_t>((height - 1 - y) * stride));
  }
  return rgba;
}

Status Renderer::writePng(const std::filesystem::path& path, const std::vector<uint8_t>& rgba, int width, int height) {
  if (rgba.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 4 ||
      !stbi_write_png(path.string().c_str(), width, height, 4, rgba.data(), width * 4)) {
    return makeError(ErrorCode::PackIoError, "cannot write the picture " + path.string());
  }
  return Ok{};
}

}  // namespace brittle
