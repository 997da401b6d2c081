// Fixtures.h — tiny hand-made meshes, analytic cases and broken inputs shared by the test suites.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/database/Material.h"

namespace brittle::testing {

/// Closed, outward axis-aligned box [0,sx]×[0,sy]×[0,sz]: 8 vertices, 12 triangles.
TriangleMesh makeBoxSurface(double sx, double sy, double sz);

/// Closed, outward icosphere of the given radius centred at the origin; level 0 is the
/// icosahedron (20 faces), each level multiplies the face count by 4.
TriangleMesh makeIcosphere(double radius, int level);

/// Structured tet mesh of the box [0,sx]×[0,sy]×[0,sz] with nx×ny×nz cells, 6 positive tets per
/// cell (Kuhn subdivision, conforming).
TetMesh makeBoxTetMesh(double sx, double sy, double sz, int nx, int ny, int nz);

/// The unit cube scaled to [0,sx]×[0,sy]×[0,sz] split into 5 positive tets: four corner tets
/// (volume sx·sy·sz/6 each) around a central one (sx·sy·sz/3) whose four faces they share. Node i
/// is the corner (i&1, i&2, i&4); the face diagonals all join the odd corners 1, 2, 4 and 7. The
/// central tet is tet 0.
TetMesh makeFiveTetBox(double sx, double sy, double sz);

/// Every directed edge (i, j) of the triangles has exactly one reverse (j, i) and appears once:
/// the surface is closed, edge-manifold and consistently oriented.
bool isClosedAndOriented(const TriangleMesh& surface);

/// A glass written out field by field, for suites that do not link the preset library
/// (precompute's MaterialLibrary): E = 70 GPa, ν = 0.22, ρ = 2500 kg/m³, σ_t = 50 MPa,
/// G_c = 8 J/m², Rayleigh α = 2 1/s and β = 1e-7 s, restitution 0.5. It passes validateMaterial.
Material makeGlassMaterial(const std::string& name = "glass");

/// Writes a mesh as OFF (vertices and triangles only).
void writeOff(const TriangleMesh& mesh, const std::filesystem::path& path);

/// A fresh, empty directory under the system temp directory, unique to this test process, and
/// removed with everything in it when the process exits (BRITTLE_KEEP_TEST_DIRS=1 keeps it).
std::filesystem::path makeTempDir(const std::string& tag);

/// Flips four bytes in the middle of the stored chunk of `dataset` (an HDF5 path) that holds row
/// `row`, in the pack at `path`: a disk fault under one chunk, which its Fletcher-32 checksum
/// then catches. False when the dataset or the chunk cannot be found.
bool damageChunk(const std::filesystem::path& path, const std::string& dataset, uint64_t row);

/// The rows of a chunk of `dataset` in the pack at `path`; 0 when it cannot be read.
uint64_t chunkRows(const std::filesystem::path& path, const std::string& dataset);

/// The repository root (BRITTLE_SOURCE_DIR if set, else the configured source directory).
std::filesystem::path sourceDir();

/// Directory holding the meshes of Debian's libcgal-demo package (data/meshes/*.off), fetched on
/// first use by tests/common/fetch_cgal_meshes.sh into the build tree. Empty path if they cannot
/// be fetched (the test then fails with the reason).
std::filesystem::path cgalDemoMeshDir();

}  // namespace brittle::testing
