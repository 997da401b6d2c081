#include "brittle/precompute/MeshIO.h"

#include <gtest/gtest.h>

#include <fstream>

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

}  // namespace
}  // namespace brittle
