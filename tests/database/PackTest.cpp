#include "brittle/database/Pack.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "brittle/core/Random.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

namespace fs = std::filesystem;

// ----- Deterministic data -----------------------------------------------------------------------

// splitmix64: a fixed, platform-independent sequence (std distributions are not).
class Bits {
 public:
  explicit Bits(uint64_t seed) : mStream(seed) {}
  uint64_t next() { return mStream.next(); }
  // Any finite double, from random bits: subnormals, −0, huge and tiny values all occur, which is
  // what a bit-exact round trip must survive.
  double anyFinite() {
    for (;;) {
      const uint64_t b = next();
      double d;
      std::memcpy(&d, &b, sizeof d);
      if (std::isfinite(d)) return d;
    }
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unitInterval(next()); }

 private:
  SplitMix64 mStream;
};

Material makeMaterial(const std::string& name, double youngsPa, double nu, double rho) {
  Material m;
  m.name = name;
  m.youngsModulusPa = youngsPa;
  m.poissonRatio = nu;
  m.densityKgPerM3 = rho;
  m.tensileStrengthPa = 4.5e7;
  m.fractureEnergyJPerM2 = 7.6467857142857;
  m.rayleighAlphaPerS = 1.0 / 3.0;
  m.rayleighBetaS = 2.2e-8;
  m.restitution = 0.55;
  m.source = "test fixture: " + name + " (values chosen to have full 53-bit mantissas)";
  return m;
}

ObjectAsset makeObject(const std::string& name, const Material& material, int nx, int ny, int nz, int modeCount,
                       uint64_t seed, ElementOrder order = ElementOrder::P1) {
  Bits bits(seed);
  ObjectAsset o;
  o.name = name;
  o.elementOrder = order;
  o.materialName = material.name;
  o.tetMesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, nx, ny, nz);
  // Jitter coordinates so they use all mantissa bits.
  for (Eigen::Index i = 0; i < o.tetMesh.nodes.size(); ++i) o.tetMesh.nodes.data()[i] += bits.uniform(-1e-3, 1e-3);
  const auto n = static_cast<int32_t>(o.tetMesh.nodes.rows());
  const Eigen::Index t = o.tetMesh.tets.rows();
  o.surfaceFaces.resize(2 * nx * ny + 2 * ny * nz + 2 * nx * nz, 3);
  for (Eigen::Index f = 0; f < o.surfaceFaces.rows(); ++f) {
    for (int c = 0; c < 3; ++c) o.surfaceFaces(f, c) = static_cast<int32_t>(bits.next() % static_cast<uint64_t>(n));
  }
  o.quality = {n,
               t,
               o.surfaceFaces.rows(),
               bits.uniform(5, 40),
               bits.uniform(120, 170),
               bits.uniform(0.7, 3),
               bits.uniform(0.6, 1.2),
               bits.uniform(1e-9, 1e-6)};
  o.massProperties = computeTetMassProperties(o.tetMesh, material.densityKgPerM3);
  // Break the symmetry of the tensors so that a transposed layout would be caught.
  o.massProperties.inertiaKgM2(0, 1) += 1e-7;
  o.massProperties.secondMomentM5(2, 0) -= 3e-11;

  ModalBasis& m = o.modal;
  m.eigenvaluesRad2PerS2.resize(modeCount);
  m.frequenciesHz.resize(modeCount);
  m.residuals.resize(modeCount);
  for (int k = 0; k < modeCount; ++k) {
    m.eigenvaluesRad2PerS2(k) = bits.uniform(1e6, 1e10);
    m.frequenciesHz(k) = std::sqrt(m.eigenvaluesRad2PerS2(k)) / (2.0 * 3.141592653589793);
    m.residuals(k) = bits.uniform(0, 1e-9);
  }
  m.orthonormalityError = bits.uniform(0, 1e-12);
  m.modes.resize(3 * femNodeCount(o.tetMesh, order), modeCount);
  for (Eigen::Index i = 0; i < m.modes.size(); ++i) m.modes.data()[i] = bits.anyFinite();
  o.stressModes.resize(6 * stressPointsPerElement(order) * t, modeCount);
  for (Eigen::Index i = 0; i < o.stressModes.size(); ++i) o.stressModes.data()[i] = bits.anyFinite();
  if (o.stressModes.size() > 1) {
    o.stressModes(0, 0) = -0.0;
    o.stressModes.data()[1] = std::numeric_limits<double>::denorm_min();
  }

  BakeRecord& b = o.bake;
  b.sourceMesh = name + ".off";
  b.targetTets = 1000 + static_cast<int64_t>(seed);
  b.cellSizeM = bits.uniform(1e-3, 1e-2);
  b.thinStretch = 1.0 + 0.75 * static_cast<double>(seed % 3);  // not a draw: the draws after it stay as they were
  o.contactSpreadFraction = 0.05 * static_cast<double>(seed % 3);  // nor this one
  b.requestedModes = modeCount;
  b.lumpedMass = (seed % 2) == 0;
  b.repaired = (seed % 2) == 1;
  b.repairVolumeChange = bits.uniform(-1e-3, 1e-3);
  b.factorization = seed % 2 ? "cholmod" : "eigen-ldlt";
  b.shift = -bits.uniform(1e3, 1e5);
  b.seed = -static_cast<int64_t>(seed) * 1234567890123LL;  // negative and beyond 32 bits
  b.meshingS = bits.uniform(0, 10);
  b.assemblyS = bits.uniform(0, 10);
  b.modalS = bits.uniform(0, 10);
  b.stressModesS = bits.uniform(0, 10);
  b.totalS = b.meshingS + b.assemblyS + b.modalS + b.stressModesS;
  b.generator = "brittle test";
  return o;
}

Pack makePack() {
  Pack p;
  p.materials.push_back(makeMaterial("glass", 7.0123456789e10, 0.22, 2500.000000001));
  p.materials.push_back(
      makeMaterial("porcelain \xc3\xa9maill\xc3\xa9"
                   "e",
                   6.6e10, 0.17, 2400.3));  // UTF-8 name
  p.objects.push_back(makeObject("plate", p.materials[0], 3, 2, 1, 7, 11));
  p.objects.push_back(makeObject("cup", p.materials[1], 2, 2, 2, 4, 12, ElementOrder::P2));
  // The cup has a baked elimination order (optional: the plate has none), here its DOFs reversed.
  ObjectAsset& cup = p.objects.back();
  cup.eliminationOrder = Eigen::VectorXi::LinSpaced(cup.modal.modes.rows(), static_cast<int>(cup.modal.modes.rows()) - 1, 0);
  return p;
}

// ----- Comparison ---------------------------------------------------------------------------------

void expectSameBits(const double* a, const double* b, Eigen::Index n, const std::string& what) {
  EXPECT_EQ(0, n == 0 ? 0 : std::memcmp(a, b, static_cast<size_t>(n) * sizeof(double))) << what;
}

template <typename MatrixA, typename MatrixB>
void expectSameDoubles(const MatrixA& a, const MatrixB& b, const std::string& what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  expectSameBits(a.data(), b.data(), a.size(), what);
}

void expectSameDouble(double a, double b, const std::string& what) { expectSameBits(&a, &b, 1, what); }

void expectSamePack(const Pack& a, const Pack& b) {
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    const Material &x = a.materials[i], &y = b.materials[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.source, y.source);
    expectSameDouble(x.youngsModulusPa, y.youngsModulusPa, "youngsModulusPa");
    expectSameDouble(x.poissonRatio, y.poissonRatio, "poissonRatio");
    expectSameDouble(x.densityKgPerM3, y.densityKgPerM3, "densityKgPerM3");
    expectSameDouble(x.tensileStrengthPa, y.tensileStrengthPa, "tensileStrengthPa");
    expectSameDouble(x.fractureEnergyJPerM2, y.fractureEnergyJPerM2, "fractureEnergyJPerM2");
    expectSameDouble(x.rayleighAlphaPerS, y.rayleighAlphaPerS, "rayleighAlphaPerS");
    expectSameDouble(x.rayleighBetaS, y.rayleighBetaS, "rayleighBetaS");
    expectSameDouble(x.restitution, y.restitution, "restitution");
  }
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const ObjectAsset &x = a.objects[i], &y = b.objects[i];
    SCOPED_TRACE("object " + x.name);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.materialName, y.materialName);
    EXPECT_EQ(x.elementOrder, y.elementOrder);
    expectSameDoubles(x.tetMesh.nodes, y.tetMesh.nodes, "nodes");
    EXPECT_TRUE(x.tetMesh.tets == y.tetMesh.tets);
    EXPECT_TRUE(x.surfaceFaces == y.surfaceFaces);

    EXPECT_EQ(x.quality.nodeCount, y.quality.nodeCount);
    EXPECT_EQ(x.quality.tetCount, y.quality.tetCount);
    EXPECT_EQ(x.quality.surfaceFaceCount, y.quality.surfaceFaceCount);
    expectSameDouble(x.quality.minDihedralDeg, y.quality.minDihedralDeg, "minDihedralDeg");
    expectSameDouble(x.quality.maxDihedralDeg, y.quality.maxDihedralDeg, "maxDihedralDeg");
    expectSameDouble(x.quality.maxRadiusEdgeRatio, y.quality.maxRadiusEdgeRatio, "maxRadiusEdgeRatio");
    expectSameDouble(x.quality.meanRadiusEdgeRatio, y.quality.meanRadiusEdgeRatio, "meanRadiusEdgeRatio");
    expectSameDouble(x.quality.minTetVolumeM3, y.quality.minTetVolumeM3, "minTetVolumeM3");

    expectSameDouble(x.massProperties.volumeM3, y.massProperties.volumeM3, "volumeM3");
    expectSameDouble(x.massProperties.massKg, y.massProperties.massKg, "massKg");
    expectSameDoubles(x.massProperties.centerOfMassM, y.massProperties.centerOfMassM, "centerOfMassM");
    expectSameDoubles(x.massProperties.inertiaKgM2, y.massProperties.inertiaKgM2, "inertiaKgM2");
    expectSameDoubles(x.massProperties.secondMomentM5, y.massProperties.secondMomentM5, "secondMomentM5");

    expectSameDoubles(x.modal.eigenvaluesRad2PerS2, y.modal.eigenvaluesRad2PerS2, "eigenvalues");
    expectSameDoubles(x.modal.frequenciesHz, y.modal.frequenciesHz, "frequencies");
    expectSameDoubles(x.modal.residuals, y.modal.residuals, "residuals");
    expectSameDouble(x.modal.orthonormalityError, y.modal.orthonormalityError, "orthonormalityError");
    expectSameDoubles(x.modal.modes, y.modal.modes, "modes");
    expectSameDoubles(x.stressModes, y.stressModes, "stressModes");
    ASSERT_EQ(x.eliminationOrder.size(), y.eliminationOrder.size());
    EXPECT_TRUE(x.eliminationOrder == y.eliminationOrder);

    EXPECT_EQ(x.bake.sourceMesh, y.bake.sourceMesh);
    EXPECT_EQ(x.bake.targetTets, y.bake.targetTets);
    expectSameDouble(x.bake.cellSizeM, y.bake.cellSizeM, "cellSizeM");
    expectSameDouble(x.bake.thinStretch, y.bake.thinStretch, "thinStretch");
    expectSameDouble(x.contactSpreadFraction, y.contactSpreadFraction, "contactSpreadFraction");
    EXPECT_EQ(x.bake.requestedModes, y.bake.requestedModes);
    EXPECT_EQ(x.bake.lumpedMass, y.bake.lumpedMass);
    EXPECT_EQ(x.bake.repaired, y.bake.repaired);
    expectSameDouble(x.bake.repairVolumeChange, y.bake.repairVolumeChange, "repairVolumeChange");
    EXPECT_EQ(x.bake.factorization, y.bake.factorization);
    expectSameDouble(x.bake.shift, y.bake.shift, "shift");
    EXPECT_EQ(x.bake.seed, y.bake.seed);
    expectSameDouble(x.bake.meshingS, y.bake.meshingS, "meshingS");
    expectSameDouble(x.bake.assemblyS, y.bake.assemblyS, "assemblyS");
    expectSameDouble(x.bake.modalS, y.bake.modalS, "modalS");
    expectSameDouble(x.bake.stressModesS, y.bake.stressModesS, "stressModesS");
    expectSameDouble(x.bake.totalS, y.bake.totalS, "totalS");
    EXPECT_EQ(x.bake.generator, y.bake.generator);
  }
}

// ----- File helpers -------------------------------------------------------------------------------

std::string fileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<fs::path> temporaryFiles(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) out.push_back(entry.path());
  }
  return out;
}

// Opens the pack read-write with the HDF5 C API, the way a damaged or foreign file would be made.
void editPack(const fs::path& path, const std::function<void(hid_t)>& edit) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  edit(file);
  ASSERT_GE(H5Fclose(file), 0);
}

void replaceStringAttribute(hid_t file, const char* name, const std::string& value) {
  ASSERT_GE(H5Adelete(file, name), 0);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size());
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(attr, 0);
  EXPECT_GE(H5Awrite(attr, type, value.data()), 0);
  H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
}

// Overwrites one element of an existing dataset (through its filters, so the checksum stays valid).
template <typename T>
void writeElement(hid_t file, const char* path, hid_t memType, std::vector<hsize_t> index, T value) {
  const hid_t dset = H5Dopen2(file, path, H5P_DEFAULT);
  ASSERT_GE(dset, 0);
  const hid_t fileSpace = H5Dget_space(dset);
  std::vector<hsize_t> count(index.size(), 1);
  ASSERT_GE(H5Sselect_hyperslab(fileSpace, H5S_SELECT_SET, index.data(), nullptr, count.data(), nullptr), 0);
  const hsize_t one = 1;
  const hid_t memSpace = H5Screate_simple(1, &one, nullptr);
  EXPECT_GE(H5Dwrite(dset, memType, memSpace, fileSpace, H5P_DEFAULT, &value), 0);
  H5Sclose(memSpace);
  H5Sclose(fileSpace);
  H5Dclose(dset);
}

// Overwrites the root's version attribute.
void writeVersion(hid_t file, int version) {
  const hid_t attr = H5Aopen(file, "version", H5P_DEFAULT);
  ASSERT_GE(attr, 0);
  EXPECT_GE(H5Awrite(attr, H5T_NATIVE_INT, &version), 0);
  H5Aclose(attr);
}

class PackTest : public ::testing::Test {
 protected:
  void SetUp() override {
    mDir = testing::makeTempDir("pack");
    mPath = mDir / "objects.pack.h5";
  }
  void TearDown() override {
    EXPECT_TRUE(temporaryFiles(mDir).empty()) << "a temporary file was left behind";
    std::error_code ec;
    fs::remove_all(mDir, ec);
  }

  void writeValidPack() {
    const Status s = writePack(makePack(), mPath);
    ASSERT_TRUE(s.ok()) << s.error().message;
  }

  // Reads the pack and expects the given error code and a message containing `mentions`.
  void expectReadError(ErrorCode code, const std::string& mentions) {
    const Result<Pack> r = readPack(mPath);
    ASSERT_FALSE(r.ok()) << "expected " << errorCodeName(code);
    EXPECT_EQ(r.error().code, code) << errorCodeName(r.error().code) << ": " << r.error().message;
    EXPECT_NE(r.error().message.find(mentions), std::string::npos)
        << "message '" << r.error().message << "' does not mention '" << mentions << "'";
  }

  fs::path mDir;
  fs::path mPath;
};

// ----- Round trips --------------------------------------------------------------------------------

TEST_F(PackTest, RoundTripIsBitExact) {
  const Pack pack = makePack();
  const Status s = writePack(pack, mPath);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  expectSamePack(pack, read.value());
}

TEST_F(PackTest, WritingIsDeterministic) {
  // Same pack ⇒ same bytes, so bakes can be compared by hash. The pause crosses a second
  // boundary, which would show up if object headers carried modification times.
  ASSERT_TRUE(writePack(makePack(), mPath).ok());
  const std::string first = fileBytes(mPath);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  ASSERT_TRUE(writePack(makePack(), mPath).ok());
  EXPECT_TRUE(first == fileBytes(mPath)) << "two writes of the same pack differ";
}

TEST_F(PackTest, EmptyPackRoundTrips) {
  const Status s = writePack(Pack{}, mPath);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_TRUE(read.value().materials.empty());
  EXPECT_TRUE(read.value().objects.empty());
}

TEST_F(PackTest, ObjectWithoutModesRoundTrips) {
  // Rigid debris has r = 0: modes is 3N by 0 and stress modes 6T by 0.
  Pack pack = makePack();
  pack.objects.push_back(makeObject("debris", pack.materials[0], 1, 1, 1, 0, 13));
  pack.objects.push_back(makeObject("chip", pack.materials[1], 1, 1, 1, 0, 14));
  const Status s = writePack(pack, mPath);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  expectSamePack(pack, read.value());
  EXPECT_EQ(read.value().objects[2].modal.modes.rows(), 3 * 8);
  EXPECT_EQ(read.value().objects[2].modal.modes.cols(), 0);
}

TEST_F(PackTest, PackWithOnlyModelessObjectsRoundTrips) {
  Pack pack;
  pack.materials.push_back(makeMaterial("glass", 7e10, 0.22, 2500));
  pack.objects.push_back(makeObject("debris", pack.materials[0], 1, 1, 1, 0, 15));
  ASSERT_TRUE(writePack(pack, mPath).ok());
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  expectSamePack(pack, read.value());
}

TEST_F(PackTest, FileStatesFormatVersionAndUnits) {
  writeValidPack();
  const hid_t file = H5Fopen(mPath.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  int version = 0;
  const hid_t attr = H5Aopen(file, "version", H5P_DEFAULT);
  ASSERT_GE(attr, 0);
  EXPECT_GE(H5Aread(attr, H5T_NATIVE_INT, &version), 0);
  EXPECT_EQ(version, kPackVersion);
  H5Aclose(attr);
  for (const char* name : {"format", "length_unit", "stress_unit", "energy_per_area_unit", "generator"}) {
    EXPECT_GT(H5Aexists(file, name), 0) << name;
  }
  // Every dataset carries the Fletcher-32 filter.
  const hid_t dset = H5Dopen2(file, "/objects/stress_modes", H5P_DEFAULT);
  ASSERT_GE(dset, 0);
  const hid_t dcpl = H5Dget_create_plist(dset);
  unsigned flags = 0;
  size_t nelmts = 0;
  EXPECT_GE(H5Pget_filter_by_id2(dcpl, H5Z_FILTER_FLETCHER32, &flags, &nelmts, nullptr, 0, nullptr, nullptr), 0);
  EXPECT_GE(H5Pget_filter_by_id2(dcpl, H5Z_FILTER_DEFLATE, &flags, &nelmts, nullptr, 0, nullptr, nullptr), 0);
  H5Pclose(dcpl);
  H5Dclose(dset);
  H5Fclose(file);
}

// ----- Atomic writes and writer validation --------------------------------------------------------

TEST_F(PackTest, MissingDirectoryFailsAndLeavesNothing) {
  const fs::path target = mDir / "no-such-dir" / "pack.h5";
  const Status s = writePack(makePack(), target);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::PackIoError);
  EXPECT_NE(s.error().message.find("no-such-dir"), std::string::npos) << s.error().message;
  EXPECT_FALSE(fs::exists(target.parent_path()));
  EXPECT_TRUE(fs::is_empty(mDir));
}

TEST_F(PackTest, FailedRenameRemovesTheTemporaryFile) {
  // A non-empty directory at the target: the temporary file is complete, the rename fails.
  fs::create_directories(mPath / "occupied");
  const Status s = writePack(makePack(), mPath);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::PackIoError);
  EXPECT_TRUE(fs::is_directory(mPath / "occupied"));
}

TEST_F(PackTest, InvalidInputLeavesExistingPackByteIdentical) {
  writeValidPack();
  const std::string before = fileBytes(mPath);

  struct Case {
    const char* what;
    const char* mentions;
    std::function<void(Pack&)> breakIt;
  };
  const Case cases[] = {
      {"unknown material", "marble", [](Pack& p) { p.objects[1].materialName = "marble"; }},
      {"modes rows", "modal.modes", [](Pack& p) { p.objects[0].modal.modes.conservativeResize(5, Eigen::NoChange); }},
      {"modes cols", "modal.modes", [](Pack& p) { p.objects[0].modal.modes.conservativeResize(Eigen::NoChange, 2); }},
      {"stress rows", "stressModes", [](Pack& p) { p.objects[1].stressModes.conservativeResize(6, Eigen::NoChange); }},
      {"eigenvalue count", "eigenvalues", [](Pack& p) { p.objects[0].modal.eigenvaluesRad2PerS2.resize(3); }},
      {"frequency count", "frequencies", [](Pack& p) { p.objects[0].modal.frequenciesHz.resize(2); }},
      {"tet index", "tetMesh.tets", [](Pack& p) { p.objects[0].tetMesh.tets(3, 2) = 100000; }},
      {"negative face index", "surfaceFaces", [](Pack& p) { p.objects[1].surfaceFaces(0, 0) = -1; }},
      {"NaN node", "tetMesh.nodes", [](Pack& p) { p.objects[0].tetMesh.nodes(2, 1) = std::nan(""); }},
      {"infinite stress mode", "stressModes",
       [](Pack& p) { p.objects[1].stressModes(0, 0) = std::numeric_limits<double>::infinity(); }},
      {"NaN timing", "bake.totalS", [](Pack& p) { p.objects[1].bake.totalS = std::nan(""); }},
      {"NaN inertia", "inertiaKgM2", [](Pack& p) { p.objects[0].massProperties.inertiaKgM2(1, 2) = std::nan(""); }},
      {"invalid material", "poisson_ratio", [](Pack& p) { p.materials[0].poissonRatio = 0.5; }},
      {"duplicate material", "glass", [](Pack& p) { p.materials[1].name = "glass"; }},
      {"duplicate object", "plate", [](Pack& p) { p.objects[1].name = "plate"; }},
      {"empty object name", "empty name", [](Pack& p) { p.objects[0].name.clear(); }},
      {"NUL in string", "NUL", [](Pack& p) { p.objects[0].bake.generator = std::string("a\0b", 3); }},
  };
  for (const Case& c : cases) {
    Pack pack = makePack();
    c.breakIt(pack);
    const Status s = writePack(pack, mPath);
    ASSERT_FALSE(s.ok()) << c.what;
    EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument) << c.what << ": " << s.error().message;
    EXPECT_NE(s.error().message.find(c.mentions), std::string::npos) << c.what << ": " << s.error().message;
    EXPECT_TRUE(before == fileBytes(mPath)) << c.what << ": the existing pack changed";
  }
}

TEST_F(PackTest, OverwriteReplacesPackWhole) {
  writeValidPack();
  Pack smaller = makePack();
  smaller.objects.pop_back();
  ASSERT_TRUE(writePack(smaller, mPath).ok());
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  expectSamePack(smaller, read.value());
}

// ----- Reader errors ------------------------------------------------------------------------------

TEST_F(PackTest, MissingFileIsFileNotFound) {
  const Result<Pack> r = readPack(mDir / "absent.h5");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::FileNotFound);
  EXPECT_NE(r.error().message.find("absent.h5"), std::string::npos);
}

TEST_F(PackTest, DirectoryIsAnIoError) {
  const Result<Pack> r = readPack(mDir);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::PackIoError);
}

TEST_F(PackTest, NotHdf5IsAnIoError) {
  std::ofstream(mPath) << "OFF\n8 12 0\nthis is not an HDF5 file\n";
  expectReadError(ErrorCode::PackIoError, "not an HDF5 file");
}

TEST_F(PackTest, EmptyFileIsAnIoError) {
  std::ofstream(mPath).close();
  expectReadError(ErrorCode::PackIoError, "not an HDF5 file");
}

TEST_F(PackTest, TruncatedFileIsCorrupt) {
  writeValidPack();
  const auto size = fs::file_size(mPath);
  for (const auto keep : {size - 1, size / 2, size / 8}) {
    writeValidPack();
    fs::resize_file(mPath, keep);
    SCOPED_TRACE("kept " + std::to_string(keep) + " of " + std::to_string(size) + " bytes");
    expectReadError(ErrorCode::PackCorrupt, "objects.pack.h5");
  }
}

TEST_F(PackTest, WrongFormatAttribute) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { replaceStringAttribute(f, "format", "other-pack"); });
  expectReadError(ErrorCode::PackFormatMismatch, "other-pack");
}

TEST_F(PackTest, MissingFormatAttribute) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { ASSERT_GE(H5Adelete(f, "format"), 0); });
  expectReadError(ErrorCode::PackFormatMismatch, "format");
}

TEST_F(PackTest, WrongUnitAttribute) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { replaceStringAttribute(f, "length_unit", "mm"); });
  expectReadError(ErrorCode::PackFormatMismatch, "length_unit");
}

TEST_F(PackTest, WrongVersion) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeVersion(f, kPackVersion + 1); });
  expectReadError(ErrorCode::PackVersionMismatch, "pack version " + std::to_string(kPackVersion + 1));
}

TEST_F(PackTest, VersionTwoPacksAreReadWithLinearElements) {
  // Before version 3 there was no element order: every object is P1.
  Pack pack = makePack();
  pack.objects.pop_back();  // the P2 object
  ASSERT_TRUE(writePack(pack, mPath).ok());
  editPack(mPath, [](hid_t f) {
    writeVersion(f, 2);
    ASSERT_GE(H5Ldelete(f, "/objects/element_order", H5P_DEFAULT), 0);
  });
  const Result<Pack> read = readPack(mPath);
  ASSERT_TRUE(read.ok()) << read.error().message;
  expectSamePack(pack, read.value());
}

TEST_F(PackTest, ElementOrderOtherThanOneOrTwoIsCorrupt) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int32_t>(f, "/objects/element_order", H5T_NATIVE_INT32, {0}, 3); });
  expectReadError(ErrorCode::PackCorrupt, "/objects/element_order");
}

TEST_F(PackTest, ModesOfTheWrongElementOrderAreRefused) {
  // The P1 object declared P2: its modes lack the mid-edge nodes and its stress modes the corners.
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int32_t>(f, "/objects/element_order", H5T_NATIVE_INT32, {0}, 2); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/modes");
  Pack pack = makePack();
  pack.objects[1].elementOrder = ElementOrder::P1;  // P2-sized modes declared P1: the writer refuses
  const Status s = writePack(pack, mPath);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(s.error().message.find("modal.modes"), std::string::npos) << s.error().message;
}

TEST_F(PackTest, AnEliminationOrderThatIsNotAPermutationIsCorrupt) {
  // The optional order (PACK_SCHEMA.md) of the cup with one DOF twice: refused by name; the writer
  // refuses it too, and a pack without the dataset reads with no order.
  writeValidPack();
  const int32_t first = makePack().objects[1].eliminationOrder[0];
  editPack(mPath, [first](hid_t f) { writeElement<int32_t>(f, "/objects/elimination_order", H5T_NATIVE_INT32, {1}, first); });
  expectReadError(ErrorCode::PackCorrupt, "/objects/elimination_order");
  Pack pack = makePack();
  pack.objects[1].eliminationOrder[1] = pack.objects[1].eliminationOrder[0];
  const Status s = writePack(pack, mPath);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(s.error().message.find("eliminationOrder"), std::string::npos) << s.error().message;
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/objects/elimination_order", H5P_DEFAULT), 0);
    ASSERT_GE(H5Ldelete(f, "/objects/elimination_order_offsets", H5P_DEFAULT), 0);
  });
  auto read = readPack(mPath);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read.value().objects[1].eliminationOrder.size(), 0);
}

TEST_F(PackTest, AThinStretchIsKeptAndAPackWithoutOneReadsAsNotStretched) {
  // The optional bake/thin_stretch (PACK_SCHEMA.md): read back as written, refused outside [1, 16]
  // by the reader (PackCorrupt, by name) and the writer, and a pack from before it reads as 1.
  Pack pack = makePack();
  pack.objects[1].bake.thinStretch = 2.5;
  ASSERT_TRUE(writePack(pack, mPath).ok());
  auto read = readPack(mPath);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read.value().objects[0].bake.thinStretch, pack.objects[0].bake.thinStretch);
  EXPECT_EQ(read.value().objects[1].bake.thinStretch, 2.5);
  editPack(mPath, [](hid_t f) { writeElement<double>(f, "/objects/bake/thin_stretch", H5T_NATIVE_DOUBLE, {1}, 0.5); });
  expectReadError(ErrorCode::PackCorrupt, "/objects/bake/thin_stretch");
  pack.objects[1].bake.thinStretch = 17.0;
  const Status s = writePack(pack, mPath);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(s.error().message.find("thinStretch"), std::string::npos) << s.error().message;
  pack.objects[1].bake.thinStretch = 2.5;
  ASSERT_TRUE(writePack(pack, mPath).ok());
  editPack(mPath, [](hid_t f) { ASSERT_GE(H5Ldelete(f, "/objects/bake/thin_stretch", H5P_DEFAULT), 0); });
  read = readPack(mPath);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read.value().objects[1].bake.thinStretch, 1.0);
}

TEST_F(PackTest, AnObjectsContactSpreadIsKeptAndAPackWithoutOneReadsAsNone) {
  // The optional contact_spread_fraction (PACK_SCHEMA.md): read back as written, refused outside
  // [0, 1) by the reader (PackCorrupt, by name) and the writer, and a pack from before it reads 0.
  Pack pack = makePack();
  pack.objects[0].contactSpreadFraction = 0.0;
  pack.objects[1].contactSpreadFraction = 0.15;
  ASSERT_TRUE(writePack(pack, mPath).ok());
  auto read = readPack(mPath);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read.value().objects[0].contactSpreadFraction, 0.0);
  EXPECT_EQ(read.value().objects[1].contactSpreadFraction, 0.15);
  for (const double bad : {-0.1, 1.0, std::nan("")}) {
    ASSERT_TRUE(writePack(pack, mPath).ok());
    editPack(mPath, [&](hid_t f) { writeElement<double>(f, "/objects/contact_spread_fraction", H5T_NATIVE_DOUBLE, {1}, bad); });
    expectReadError(ErrorCode::PackCorrupt, "/objects/contact_spread_fraction");
    Pack wrong = pack;
    wrong.objects[1].contactSpreadFraction = bad;
    const Status s = writePack(wrong, mPath);
    ASSERT_FALSE(s.ok()) << bad;
    EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(s.error().message.find("contactSpreadFraction"), std::string::npos) << s.error().message;
  }
  ASSERT_TRUE(writePack(pack, mPath).ok());
  editPack(mPath, [](hid_t f) { ASSERT_GE(H5Ldelete(f, "/objects/contact_spread_fraction", H5P_DEFAULT), 0); });
  read = readPack(mPath);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read.value().objects[1].contactSpreadFraction, 0.0);
}

TEST_F(PackTest, MissingDataset) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { ASSERT_GE(H5Ldelete(f, "/objects/tets", H5P_DEFAULT), 0); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/tets");
}

TEST_F(PackTest, MissingGroup) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { ASSERT_GE(H5Ldelete(f, "/objects/bake", H5P_DEFAULT), 0); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/bake");
}

TEST_F(PackTest, SoftLinkInPlaceOfADatasetIsRefused) {
  // Links could point outside the checked file (external links); the schema stores objects only.
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/objects/volume_m3", H5P_DEFAULT), 0);
    ASSERT_GE(H5Lcreate_soft("/objects/mass_kg", f, "/objects/volume_m3", H5P_DEFAULT, H5P_DEFAULT), 0);
  });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/volume_m3");
}

// Replaces a dataset by one of the same type and shape whose values HDF5 takes from another file:
// raw external storage, or a virtual dataset mapping the same dataset of a copy of the pack.
void storeValuesOutside(hid_t file, const char* path, const fs::path& outside, bool isVirtual) {
  const hid_t dset = H5Dopen2(file, path, H5P_DEFAULT);
  ASSERT_GE(dset, 0);
  const hid_t space = H5Dget_space(dset);
  std::vector<double> values(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
  ASSERT_GE(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Dclose(dset);
  ASSERT_GE(H5Ldelete(file, path, H5P_DEFAULT), 0);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (isVirtual) {
    EXPECT_GE(H5Pset_virtual(dcpl, space, outside.c_str(), path, space), 0);
  } else {
    std::ofstream(outside, std::ios::binary)
        .write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(double)));
    EXPECT_GE(H5Pset_external(dcpl, outside.c_str(), 0, values.size() * sizeof(double)), 0);
  }
  const hid_t created = H5Dcreate2(file, path, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  EXPECT_GE(created, 0);
  if (!isVirtual) {
    EXPECT_GE(H5Dwrite(created, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  }
  H5Dclose(created);
  H5Pclose(dcpl);
  H5Sclose(space);
}

TEST_F(PackTest, ValuesKeptInAnotherFileAreRefused) {
  // The reader took values from external storage as if they were in the pack: no checksum, and a
  // file of the pack's choosing opened (a FIFO would block the read for ever). Found by
  // tests/fuzz/fuzz_pack_edits. A virtual dataset was refused only because HDF5 reports no stored
  // bytes for it.
  for (const bool isVirtual : {false, true}) {
    SCOPED_TRACE(isVirtual ? "virtual dataset" : "external storage");
    writeValidPack();
    const fs::path outside = mDir / (isVirtual ? "copy.h5" : "nodes.raw");
    if (isVirtual) fs::copy_file(mPath, outside, fs::copy_options::overwrite_existing);
    editPack(mPath, [&](hid_t f) { storeValuesOutside(f, "/objects/nodes", outside, isVirtual); });
    expectReadError(ErrorCode::PackShapeMismatch, "/objects/nodes");
  }
}

TEST_F(PackTest, WrongShape) {
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/objects/mass_kg", H5P_DEFAULT), 0);
    const hsize_t dims = 3;  // the pack has 2 objects
    const hid_t space = H5Screate_simple(1, &dims, nullptr);
    const hid_t dset = H5Dcreate2(f, "/objects/mass_kg", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const double values[3] = {1, 2, 3};
    EXPECT_GE(H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    H5Dclose(dset);
    H5Sclose(space);
  });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/mass_kg");
}

TEST_F(PackTest, WrongType) {
  // float32 where float64 belongs: HDF5 would convert it, the schema forbids it.
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/objects/volume_m3", H5P_DEFAULT), 0);
    const hsize_t dims = 2;
    const hid_t space = H5Screate_simple(1, &dims, nullptr);
    const hid_t dset =
        H5Dcreate2(f, "/objects/volume_m3", H5T_IEEE_F32LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const float values[2] = {1, 2};
    EXPECT_GE(H5Dwrite(dset, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    H5Dclose(dset);
    H5Sclose(space);
  });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/volume_m3");
}

TEST_F(PackTest, NonMonotoneOffsets) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int64_t>(f, "/objects/node_offsets", H5T_NATIVE_INT64, {1}, -5); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/node_offsets");
}

TEST_F(PackTest, OffsetsThatDoNotEndAtTheRowCount) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int64_t>(f, "/objects/tet_offsets", H5T_NATIVE_INT64, {2}, 7); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/tet_offsets");
}

TEST_F(PackTest, ModeBlockSizeDisagreesWithCounts) {
  // Shifting one boundary of the modal offsets keeps them monotone but breaks 3N·r per object.
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int64_t>(f, "/objects/mode_offsets", H5T_NATIVE_INT64, {1}, 6); });
  expectReadError(ErrorCode::PackShapeMismatch, "/objects/modes");
}

TEST_F(PackTest, NonFiniteValue) {
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    writeElement<double>(f, "/objects/nodes", H5T_NATIVE_DOUBLE, {5, 1}, std::numeric_limits<double>::quiet_NaN());
  });
  expectReadError(ErrorCode::PackCorrupt, "/objects/nodes");
  expectReadError(ErrorCode::PackCorrupt, "[5, 1]");
}

TEST_F(PackTest, InfiniteMaterialValue) {
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    writeElement<double>(f, "/materials/density_kg_per_m3", H5T_NATIVE_DOUBLE, {1},
                         -std::numeric_limits<double>::infinity());
  });
  expectReadError(ErrorCode::PackCorrupt, "/materials/density_kg_per_m3");
}

TEST_F(PackTest, TetIndexOutOfRange) {
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int32_t>(f, "/objects/tets", H5T_NATIVE_INT32, {3, 2}, 1000000); });
  expectReadError(ErrorCode::PackCorrupt, "/objects/tets");
}

TEST_F(PackTest, FaceIndexOutOfRange) {
  // Index 30 exists in the concatenated node array, but not in the first object (24 nodes).
  writeValidPack();
  editPack(mPath, [](hid_t f) { writeElement<int32_t>(f, "/objects/surface_faces", H5T_NATIVE_INT32, {0, 1}, 30); });
  expectReadError(ErrorCode::PackCorrupt, "/objects/surface_faces");
}

TEST_F(PackTest, UnknownMaterialReference) {
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/materials/name", H5P_DEFAULT), 0);
    const hsize_t dims = 2;
    const hid_t space = H5Screate_simple(1, &dims, nullptr);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, 6);
    const hid_t dset = H5Dcreate2(f, "/materials/name", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, "glass\0stone\0"), 0);
    H5Dclose(dset);
    H5Tclose(type);
    H5Sclose(space);
  });
  expectReadError(ErrorCode::PackCorrupt, "porcelain");
}

TEST_F(PackTest, AbsurdDatasetSizeIsRejectedBeforeAllocating) {
  // 10^12 doubles (8 TB) declared, nothing stored: must fail, not try to allocate.
  writeValidPack();
  editPack(mPath, [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/objects/modes", H5P_DEFAULT), 0);
    const hsize_t dims = 1000000000000ULL;
    const hsize_t chunk = 1024;
    const hid_t space = H5Screate_simple(1, &dims, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, &chunk);
    const hid_t dset = H5Dcreate2(f, "/objects/modes", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    EXPECT_GE(dset, 0);
    H5Dclose(dset);
    H5Pclose(dcpl);
    H5Sclose(space);
  });
  expectReadError(ErrorCode::PackCorrupt, "/objects/modes");
}

TEST_F(PackTest, FlippedBytesInAChunkAreCaughtByTheChecksum) {
  writeValidPack();
  ASSERT_TRUE(testing::damageChunk(mPath, "/objects/nodes", 0));
  expectReadError(ErrorCode::PackCorrupt, "/objects/nodes");
}

TEST_F(PackTest, FlippedChecksumItselfIsCaught) {
  // The last four bytes of a chunk are its Fletcher-32 checksum.
  writeValidPack();
  haddr_t address = 0;
  hsize_t size = 0;
  {
    const hid_t file = H5Fopen(mPath.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    const hid_t dset = H5Dopen2(file, "/objects/stress_modes", H5P_DEFAULT);
    const hid_t space = H5Dget_space(dset);
    hsize_t offset[1] = {0};
    unsigned filterMask = 0;
    EXPECT_GE(H5Dget_chunk_info(dset, space, 0, offset, &filterMask, &address, &size), 0);
    H5Sclose(space);
    H5Dclose(dset);
    H5Fclose(file);
  }
  ASSERT_GT(size, 4u);
  {
    std::fstream io(mPath, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(static_cast<std::streamoff>(address + size - 1));
    char b = 0;
    io.seekg(static_cast<std::streamoff>(address + size - 1));
    io.read(&b, 1);
    b = static_cast<char>(b ^ 0x01);
    io.seekp(static_cast<std::streamoff>(address + size - 1));
    io.write(&b, 1);
    ASSERT_TRUE(io.good());
  }
  expectReadError(ErrorCode::PackCorrupt, "/objects/stress_modes");
}

}  // namespace
}  // namespace brittle
