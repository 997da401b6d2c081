#include "brittle/precompute/MeshIO.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

class MeshIOTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = testing::makeTempDir("meshio");
  void write(const std::string& name, const std::string& text) { std::ofstream(dir / name) << text; }
};

TEST_F(MeshIOTest, RoundTripsEveryFormat) {
  const auto box = testing::makeBoxSurface(0.3, 0.2, 0.1);
  for (const char* ext : {"off", "obj", "ply", "stl", "OFF"}) {
    const auto path = dir / (std::string("box.") + ext);
    ASSERT_TRUE(writeSurfaceMesh(box, path).ok()) << ext;
    auto read = readSurfaceMesh(path);
    ASSERT_TRUE(read.ok()) << ext << ": " << read.error().message;
    EXPECT_EQ(read.value().faces.rows(), 12) << ext;
    EXPECT_EQ(read.value().vertices.rows(), 8) << ext;  // STL corners are merged back
    EXPECT_NEAR(computeSurfaceMassProperties(read.value(), 1.0).volumeM3, 0.006, 1e-7) << ext;
  }
}

TEST_F(MeshIOTest, FanTriangulatesPolygons) {
  write("quad.off", "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
  auto read = readSurfaceMesh(dir / "quad.off");
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read.value().faces.rows(), 12);
  EXPECT_NEAR(computeSurfaceMassProperties(read.value(), 1.0).volumeM3, 1.0, 1e-12);
}

TEST_F(MeshIOTest, TypedErrors) {
  EXPECT_EQ(readSurfaceMesh(dir / "missing.off").error().code, ErrorCode::FileNotFound);
  write("mesh.xyz", "1 2 3\n");
  EXPECT_EQ(readSurfaceMesh(dir / "mesh.xyz").error().code, ErrorCode::UnknownFormat);
  write("empty.off", "");
  EXPECT_EQ(readSurfaceMesh(dir / "empty.off").error().code, ErrorCode::EmptyMesh);
  write("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(readSurfaceMesh(dir / "nofaces.off").error().code, ErrorCode::EmptyMesh);
  write("nan.off", "OFF\n4 4 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  const auto nan = readSurfaceMesh(dir / "nan.off");
  ASSERT_FALSE(nan.ok());
  EXPECT_EQ(nan.error().code, ErrorCode::NonFiniteValue);
  EXPECT_NE(nan.error().message.find("line 5"), std::string::npos) << nan.error().message;
  write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n");
  EXPECT_EQ(readSurfaceMesh(dir / "nan.obj").error().code, ErrorCode::NonFiniteValue);
  write("garbage.off", "OFF\n4 4 0\n0 0 zero\n");
  EXPECT_EQ(readSurfaceMesh(dir / "garbage.off").error().code, ErrorCode::ParseError);
  write("badindex.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  EXPECT_EQ(readSurfaceMesh(dir / "badindex.off").error().code, ErrorCode::ParseError);
  EXPECT_EQ(writeSurfaceMesh(testing::makeBoxSurface(1, 1, 1), dir / "box.abc").error().code, ErrorCode::UnknownFormat);
}

// ----- OFF and PLY are read by brittle (CGAL 5.5's readers were unsafe on these inputs, found by
// tests/fuzz/fuzz_mesh_reader). Each input below crashed, hung or overflowed in the old reader.

TEST_F(MeshIOTest, OffVariantsCommentsAndColoursRead) {
  write("coloured.off", "# comment first\nCOFF 4 4 0\n0 0 0 255 0 0 255\n1 0 0 0.5 0 0#colour as floats\n"
                        "0 1 0 9\n\n0 0 1 9 9 9 255\n3 0 2 1 1 0 0\n3 0 1 3\n3 0 3 2 # a comment\n3 1 2 3\n");
  auto coloured = readSurfaceMesh(dir / "coloured.off");
  ASSERT_TRUE(coloured.ok()) << coloured.error().message;
  EXPECT_EQ(coloured.value().faces.rows(), 4);
  EXPECT_NEAR(computeSurfaceMassProperties(coloured.value(), 1.0).volumeM3, 1.0 / 6.0, 1e-15);
  // Homogeneous coordinates are divided by w.
  write("h.off", "4OFF\n4 4 0\n0 0 0 2\n2 0 0 2\n0 2 0 2\n0 0 2 2\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  auto homogeneous = readSurfaceMesh(dir / "h.off");
  ASSERT_TRUE(homogeneous.ok()) << homogeneous.error().message;
  EXPECT_EQ(homogeneous.value().vertices(1, 0), 1.0);
  write("binary.off", "OFF BINARY\n");
  EXPECT_EQ(readSurfaceMesh(dir / "binary.off").error().code, ErrorCode::ParseError);
}

TEST_F(MeshIOTest, OffCountsBeyondTheFileAreRefusedBeforeAllocating) {
  // CGAL sized its arrays from these counts first: gigabytes for a 30-byte file.
  write("counts.off", "OFF\n100000000 100000000 0\n");
  const auto r = readSurfaceMesh(dir / "counts.off");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::ParseError);
  EXPECT_NE(r.error().message.find("declares 100000000 vertices"), std::string::npos) << r.error().message;
}

TEST_F(MeshIOTest, OffFaceIndexBeyondEveryIntegerIsAParseError) {
  // CGAL cast this index from double to size_t: undefined behaviour.
  write("huge.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
                    "3 1 2 66666666666666666666666666666666666666663\n");
  const auto r = readSurfaceMesh(dir / "huge.off");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::ParseError);
  EXPECT_NE(r.error().message.find("line 10"), std::string::npos) << r.error().message;
  write("negative.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n");
  EXPECT_EQ(readSurfaceMesh(dir / "negative.off").error().code, ErrorCode::ParseError);
}

TEST_F(MeshIOTest, MalformedCoffColourLineIsAParseError) {
  // CGAL read past the end of a vector on the non-numeric vertex line (heap-buffer-overflow).
  write("colour.off", "COFF\n4 4 0\n\xa6\xa6\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
                      "0 0 1 9 9 9 255\n3 0 2 1 1 0 0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const auto r = readSurfaceMesh(dir / "colour.off");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::ParseError);
  EXPECT_NE(r.error().message.find("line 3"), std::string::npos) << r.error().message;
}

// A tetrahedron's header: 4 vertices with a colour, `faces` faces, and an empty element to skip.
std::string plyHeader(const std::string& format, const std::string& vertexType, const std::string& indexTypes,
                      const std::string& faces = "4") {
  return "ply\nformat " + format + " 1.0\ncomment a tetrahedron\nelement vertex 4\nproperty " + vertexType +
         " x\nproperty " + vertexType + " y\nproperty " + vertexType + " z\nproperty uchar red\nelement face " + faces +
         "\nproperty list " + indexTypes + " vertex_indices\nelement edge 0\nproperty int vertex1\nend_header\n";
}

template <typename T>
void append(std::string& bytes, T value, bool bigEndian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (bigEndian) std::reverse(raw, raw + sizeof(T));
  bytes.append(raw, sizeof(T));
}

TEST_F(MeshIOTest, PlyReadsEveryEncoding) {
  const double corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string ascii = plyHeader("ascii", "float", "uchar int");
  for (const auto& c : corners) ascii += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + " 7\n";
  for (const auto& f : faces) ascii += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  write("ascii.ply", ascii);
  for (bool big : {false, true}) {
    std::string binary = plyHeader(big ? "binary_big_endian" : "binary_little_endian", "double", "ushort uint");
    for (const auto& c : corners) {
      for (double x : c) append(binary, x, big);
      append(binary, uint8_t{7}, big);
    }
    for (const auto& f : faces) {
      append(binary, uint16_t{3}, big);
      for (int i : f) append(binary, static_cast<uint32_t>(i), big);
    }
    write(big ? "big.ply" : "little.ply", binary);
  }
  for (const char* name : {"ascii.ply", "little.ply", "big.ply"}) {
    auto read = readSurfaceMesh(dir / name);
    ASSERT_TRUE(read.ok()) << name << ": " << read.error().message;
    EXPECT_EQ(read.value().faces.rows(), 4) << name;
    EXPECT_NEAR(computeSurfaceMassProperties(read.value(), 1.0).volumeM3, 1.0 / 6.0, 1e-15) << name;
  }
}

TEST_F(MeshIOTest, PlyPropertyBeforeAnyElementIsAParseError) {
  // CGAL wrote through back() of its empty element list.
  write("early.ply", "ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nend_header\n0\n");
  const auto r = readSurfaceMesh(dir / "early.ply");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::ParseError);
  EXPECT_NE(r.error().message.find("header line 3"), std::string::npos) << r.error().message;
}

TEST_F(MeshIOTest, PlyCountsBeyondTheFileAreRefused) {
  // 2^64 - 1 vertices without properties: CGAL looped, adding a point each time, reading nothing.
  write("noprops.ply", "ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nend_header\n");
  EXPECT_EQ(readSurfaceMesh(dir / "noprops.ply").error().code, ErrorCode::ParseError);
  write("faces.ply", plyHeader("ascii", "float", "uchar int", "4000000000") + "0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n3 0 1 2\n");
  const auto faces = readSurfaceMesh(dir / "faces.ply");
  ASSERT_FALSE(faces.ok());
  EXPECT_EQ(faces.error().code, ErrorCode::ParseError);
  EXPECT_NE(faces.error().message.find("more than the file holds"), std::string::npos) << faces.error().message;
  // A list of 2^32 - 1 indices in a file of a few bytes: CGAL sized a buffer from it.
  std::string list = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
  for (float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(list, x, false);
  append(list, uint32_t{0xffffffff}, false);
  for (int32_t i : {0, 1, 2}) append(list, i, false);
  write("list.ply", list);
  const auto longList = readSurfaceMesh(dir / "list.ply");
  ASSERT_FALSE(longList.ok());
  EXPECT_EQ(longList.error().code, ErrorCode::ParseError);
  EXPECT_NE(longList.error().message.find("list length"), std::string::npos) << longList.error().message;
}

}  // namespace
}  // namespace brittle
