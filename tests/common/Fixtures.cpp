#include "brittle/testing/Fixtures.h"

#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>

namespace brittle::testing {

TriangleMesh makeBoxSurface(double sx, double sy, double sz) {
  TriangleMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << (i & 1 ? sx : 0.0), (i & 2 ? sy : 0.0), (i & 4 ? sz : 0.0);
  }
  // Two outward triangles per face (counter-clockwise seen from outside).
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3,  // z = 0
      4, 5, 6, 5, 7, 6,         // z = sz
      0, 1, 4, 1, 5, 4,         // y = 0
      2, 6, 3, 3, 6, 7,         // y = sy
      0, 4, 2, 2, 4, 6,         // x = 0
      1, 3, 5, 3, 7, 5;         // x = sx
  return m;
}

TriangleMesh makeIcosphere(double radius, int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  TriangleMesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = radius * v[i];
  m.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) {
    m.faces.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  }
  return m;
}

TetMesh makeBoxTetMesh(double sx, double sy, double sz, int nx, int ny, int nz) {
  TetMesh m;
  const int px = nx + 1, py = ny + 1, pz = nz + 1;
  m.nodes.resize(px * py * pz, 3);
  auto id = [&](int i, int j, int k) { return i + px * (j + py * k); };
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i) m.nodes.row(id(i, j, k)) << sx * i / nx, sy * j / ny, sz * k / nz;
  // Kuhn subdivision: the six tets along the main diagonal 0→7 of each cell.
  static const int kPaths[6][3] = {{1, 3, 7}, {1, 5, 7}, {2, 3, 7}, {2, 6, 7}, {4, 5, 7}, {4, 6, 7}};
  m.tets.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        auto corner = [&](int c) { return id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)); };
        for (const auto& p : kPaths) {
          std::array<int, 4> tet = {corner(0), corner(p[0]), corner(p[1]), corner(p[2])};
          const Eigen::Vector3d a = m.nodes.row(tet[0]), b = m.nodes.row(tet[1]),
                                c = m.nodes.row(tet[2]), d = m.nodes.row(tet[3]);
          if ((b - a).dot((c - a).cross(d - a)) < 0) std::swap(tet[2], tet[3]);
          m.tets.row(t++) << tet[0], tet[1], tet[2], tet[3];
        }
      }
  return m;
}

void writeOff(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path);
  out.precision(17);
  out << "OFF\n" << mesh.vertices.rows() << ' ' << mesh.faces.rows() << " 0\n";
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i) {
    out << mesh.vertices(i, 0) << ' ' << mesh.vertices(i, 1) << ' ' << mesh.vertices(i, 2) << '\n';
  }
  for (Eigen::Index i = 0; i < mesh.faces.rows(); ++i) {
    out << "3 " << mesh.faces(i, 0) << ' ' << mesh.faces(i, 1) << ' ' << mesh.faces(i, 2) << '\n';
  }
}

std::filesystem::path makeTempDir(const std::string& tag) {
  static int counter = 0;
  auto dir = std::filesystem::temp_directory_path() /
             ("brittle-test-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::filesystem::path sourceDir() {
  const char* dir = std::getenv("BRITTLE_SOURCE_DIR");
  return dir ? std::filesystem::path(dir) : std::filesystem::path(BRITTLE_TEST_SOURCE_DIR);
}

std::filesystem::path cgalDemoMeshDir() {
  const char* bin = std::getenv("BRITTLE_BINARY_DIR");
  const std::filesystem::path root = bin ? std::filesystem::path(bin) : std::filesystem::path(BRITTLE_TEST_BINARY_DIR);
  const auto dir = root / "test-data" / "cgal" / "data" / "meshes";
  if (std::filesystem::exists(dir / ".complete")) return dir;
  const std::string cmd = "bash \"" + (sourceDir() / "tests/common/fetch_cgal_meshes.sh").string() +
                          "\" \"" + (root / "test-data" / "cgal").string() + "\"";
  if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(dir)) return {};
  return dir;
}

}  // namespace brittle::testing
