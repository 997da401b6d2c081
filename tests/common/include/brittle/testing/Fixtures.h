// Fixtures.h — tiny hand-made meshes, analytic cases and broken inputs shared by the test suites.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "brittle/core/MeshTypes.h"

namespace brittle::testing {

/// Closed, outward axis-aligned box [0,sx]×[0,sy]×[0,sz]: 8 vertices, 12 triangles.
TriangleMesh makeBoxSurface(double sx, double sy, double sz);

/// Closed, outward icosphere of the given radius centred at the origin; level 0 is the
/// icosahedron (20 faces), each level multiplies the face count by 4.
TriangleMesh makeIcosphere(double radius, int level);

/// Structured tet mesh of the box [0,sx]×[0,sy]×[0,sz] with nx×ny×nz cells, 6 positive tets per
/// cell (Kuhn subdivision, conforming).
TetMesh makeBoxTetMesh(double sx, double sy, double sz, int nx, int ny, int nz);

/// Writes a mesh as OFF (vertices and triangles only).
void writeOff(const TriangleMesh& mesh, const std::filesystem::path& path);

/// A fresh, empty directory under the system temp directory, unique to this test process.
std::filesystem::path makeTempDir(const std::string& tag);

/// The repository root (BRITTLE_SOURCE_DIR if set, else the configured source directory).
std::filesystem::path sourceDir();

/// Directory holding the meshes of Debian's libcgal-demo package (data/meshes/*.off), fetched on
/// first use by tests/common/fetch_cgal_meshes.sh into the build tree. Empty path if they cannot
/// be fetched (the test then fails with the reason).
std::filesystem::path cgalDemoMeshDir();

}  // namespace brittle::testing
