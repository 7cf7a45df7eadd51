// The tissue surface mesh: the depth of a frame triangulated on its pixel grid, without tool
// pixels, unknown depth or bridges across depth edges; PLY, OBJ and STL as written.
#include "worker/engine/eval/surface_mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <fstream>

#include "tests/unit/temp_dir.h"

namespace endorecon::eval {
namespace {

scene::Camera Camera(int w, int h) {
  scene::Camera camera;
  camera.width = w;
  camera.height = h;
  camera.fx = camera.fy = 10;
  camera.cx = w / 2.0;
  camera.cy = h / 2.0;
  return camera;
}

TEST(SurfaceMeshTest, APlaneGivesTwoTrianglesPerPixelSquareFacingTheCamera) {
  const int w = 5, h = 4;
  const std::vector<float> depth(w * h, 50.f), rgb(w * h * 3, 0.5f);
  const SurfaceMesh mesh = TriangulateDepth(Camera(w, h), depth, rgb, {}, 100);
  EXPECT_EQ(mesh.vertex_count(), 20u);
  EXPECT_EQ(mesh.triangle_count(), 2u * (w - 1) * (h - 1));
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) EXPECT_FLOAT_EQ(mesh.xyz[3 * v + 2], -50.f);
  // Counter-clockwise seen from the camera (which looks down -z): normals point at +z.
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto p = [&](int k) {
      const auto i = mesh.triangles[3 * t + k];
      return Eigen::Vector3f(mesh.xyz[3 * i], mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2]);
    };
    EXPECT_GT((p(1) - p(0)).cross(p(2) - p(0)).z(), 0.f) << "triangle " << t;
  }
}

TEST(SurfaceMeshTest, ToolUnknownAndFarPixelsAndDepthEdgesAreLeftOut) {
  const int w = 4, h = 3;
  std::vector<float> depth(w * h, 50.f);
  const std::vector<float> rgb(w * h * 3, 0.5f);
  std::vector<std::uint8_t> tool(w * h, 0);
  tool[0] = 1;      // a tool pixel at the corner: one triangle of its square goes
  depth[3] = 0;     // unknown depth at the other top corner
  depth[11] = 100;  // the far plane (nothing rendered)
  depth[5] = 70;    // a step of 40%: every triangle touching it is an edge
  const SurfaceMesh mesh = TriangulateDepth(Camera(w, h), depth, rgb, tool, 100);
  EXPECT_EQ(mesh.vertex_count(), 9u);
  for (const auto index : mesh.triangles) {
    EXPECT_NE(mesh.xyz[3 * index + 2], -70.f) << "a triangle bridges the depth edge";
  }
  EXPECT_EQ(mesh.triangle_count(), 2u);
}

TEST(SurfaceMeshTest, FilesHoldEveryTriangle) {
  testing::TempDir dir;
  const int w = 3, h = 3;
  const std::vector<float> depth(w * h, 20.f), rgb(w * h * 3, 1.f);
  const SurfaceMesh mesh = TriangulateDepth(Camera(w, h), depth, rgb, {}, 100);
  WriteSurfaceMesh(dir.path(), mesh);
  EXPECT_EQ(std::filesystem::file_size(dir / "mesh.stl"), 84u + 50u * mesh.triangle_count());
  std::ifstream ply(dir / "mesh.ply", std::ios::binary);
  std::string header((std::istreambuf_iterator<char>(ply)), std::istreambuf_iterator<char>());
  EXPECT_NE(header.find("element vertex 9\n"), std::string::npos);
  EXPECT_NE(header.find("element face 8\n"), std::string::npos);
  std::ifstream obj(dir / "mesh.obj");
  int vertices = 0, faces = 0;
  for (std::string line; std::getline(obj, line);) {
    vertices += line.rfind("v ", 0) == 0;
    faces += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(vertices, 9);
  EXPECT_EQ(faces, 8);
}

}  // namespace
}  // namespace endorecon::eval
