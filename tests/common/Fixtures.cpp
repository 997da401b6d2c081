#include "brittle/testing/Fixtures.h"

#include "brittle/descriptors/MeshRefinement.h"

#include <hdf5.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

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
  TriangleMesh m = unitIcosphere(level);
  m.vertices *= radius;
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

TetMesh makeFiveTetBox(double sx, double sy, double sz) {
  TetMesh m;
  m.nodes.resize(8, 3);
  for (int i = 0; i < 8; ++i) m.nodes.row(i) << (i & 1 ? sx : 0.0), (i & 2 ? sy : 0.0), (i & 4 ? sz : 0.0);
  // Each corner tet is an even corner with its three neighbours; all are listed positively.
  m.tets.resize(5, 4);
  m.tets << 1, 2, 4, 7,  //
      0, 1, 2, 4,        //
      3, 2, 1, 7,        //
      5, 1, 4, 7,        //
      6, 4, 2, 7;
  return m;
}

bool isClosedAndOriented(const TriangleMesh& surface) {
  std::map<std::pair<int, int>, int> count;
  for (Eigen::Index f = 0; f < surface.faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) ++count[{surface.faces(f, k), surface.faces(f, (k + 1) % 3)}];
  }
  for (const auto& [e, c] : count) {
    const auto it = count.find({e.second, e.first});
    if (c != 1 || it == count.end() || it->second != 1) return false;
  }
  return true;
}

Material makeGlassMaterial(const std::string& name) {
  Material m;
  m.name = name;
  m.youngsModulusPa = 70e9;
  m.poissonRatio = 0.22;
  m.densityKgPerM3 = 2500.0;
  m.tensileStrengthPa = 50e6;
  m.fractureEnergyJPerM2 = 8.0;
  m.rayleighAlphaPerS = 2.0;
  m.rayleighBetaS = 1e-7;
  m.restitution = 0.5;
  m.source = "test fixture";
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

namespace {

// The directories makeTempDir made in this process, removed when it exits: test runs left every one
// behind (1 482 directories, 1.7 GB, in one machine's temp directory). BRITTLE_KEEP_TEST_DIRS=1
// keeps them, to look at a failed test's files. Unlinking files a static object still holds open
// (a pack read on demand) is harmless on the systems the tests run on.
struct MadeDirs {
  std::mutex mutex;
  std::vector<std::filesystem::path> dirs;
  int counter = 0;
  ~MadeDirs() {
    const char* keep = std::getenv("BRITTLE_KEEP_TEST_DIRS");
    if (keep != nullptr && *keep != '\0' && std::string(keep) != "0") return;
    std::error_code ec;
    for (const auto& dir : dirs) std::filesystem::remove_all(dir, ec);
  }
};

MadeDirs& madeDirs() {
  static MadeDirs made;
  return made;
}

}  // namespace

std::filesystem::path makeTempDir(const std::string& tag) {
  MadeDirs& made = madeDirs();
  std::lock_guard<std::mutex> lock(made.mutex);
  auto dir = std::filesystem::temp_directory_path() /
             ("brittle-test-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(made.counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  made.dirs.push_back(dir);
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

uint64_t chunkRows(const std::filesystem::path& path, const std::string& dataset) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return 0;
  const hid_t dset = H5Dopen2(file, dataset.c_str(), H5P_DEFAULT);
  const hid_t dcpl = dset >= 0 ? H5Dget_create_plist(dset) : -1;
  hsize_t chunk[H5S_MAX_RANK] = {0};
  const bool found = dcpl >= 0 && H5Pget_chunk(dcpl, H5S_MAX_RANK, chunk) >= 1;
  if (dcpl >= 0) H5Pclose(dcpl);
  if (dset >= 0) H5Dclose(dset);
  H5Fclose(file);
  return found ? chunk[0] : 0;
}

bool damageChunk(const std::filesystem::path& path, const std::string& dataset, uint64_t row) {
  haddr_t address = 0;
  hsize_t size = 0;
  {
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) return false;
    const hid_t dset = H5Dopen2(file, dataset.c_str(), H5P_DEFAULT);
    const hid_t space = dset >= 0 ? H5Dget_space(dset) : -1;
    const hid_t dcpl = dset >= 0 ? H5Dget_create_plist(dset) : -1;
    const int rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
    std::vector<hsize_t> chunk(static_cast<size_t>(std::max(rank, 1))), coord(chunk.size(), 0);
    bool found = rank >= 1 && dcpl >= 0 && H5Pget_chunk(dcpl, rank, chunk.data()) == rank;
    if (found) {
      coord[0] = row / chunk[0] * chunk[0];
      unsigned filterMask = 0;
      found = H5Dget_chunk_info_by_coord(dset, coord.data(), &filterMask, &address, &size) >= 0 && size > 8;
    }
    if (dcpl >= 0) H5Pclose(dcpl);
    if (space >= 0) H5Sclose(space);
    if (dset >= 0) H5Dclose(dset);
    H5Fclose(file);
    if (!found) return false;
  }
  std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
  io.seekg(static_cast<std::streamoff>(address + size / 2));
  char bytes[4];
  io.read(bytes, sizeof bytes);
  for (char& b : bytes) b = static_cast<char>(~b);
  io.seekp(static_cast<std::streamoff>(address + size / 2));
  io.write(bytes, sizeof bytes);
  return io.good();
}

}  // namespace brittle::testing
