// Gmsh import: meshes written at test time (by the Gmsh API, and by hand in msh 2.2 ASCII).
#include <gmsh.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "geometry/generators.hpp"
#include "geometry/gmsh_import.hpp"

namespace lamina::geometry {
namespace {

namespace fs = std::filesystem;

/// A per-process scratch directory for the meshes written by the tests, removed at exit.
fs::path scratch_dir() {
  struct Scratch {
    fs::path dir = fs::path(::testing::TempDir()) / ("lamina_geometry_" + std::to_string(::getpid()));
    Scratch() { fs::create_directories(dir); }
    ~Scratch() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  };
  static Scratch scratch;
  return scratch.dir;
}

/// A 2 x 1 x 0.5 block of 4 x 2 x 2 hexahedra, physical groups: volume "body", the x = 0 face
/// "left", the z = 0 face unnamed with tag 7. Written as msh `version` (binary or ASCII).
std::string write_block(const std::string& name, double version, bool binary) {
  const std::string path = (scratch_dir() / name).string();
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("block");
  const int p = gmsh::model::geo::addPoint(0, 0, 0);
  gmsh::vectorpair out;
  gmsh::model::geo::extrude({{0, p}}, 2, 0, 0, out, {4}, {}, true);
  const int line = out[1].second;
  gmsh::model::geo::extrude({{1, line}}, 0, 1, 0, out, {2}, {}, true);
  const int bottom = out[1].second;
  gmsh::model::geo::extrude({{2, bottom}}, 0, 0, 0.5, out, {2}, {}, true);
  const int volume = out[1].second;
  gmsh::model::geo::synchronize();
  gmsh::vectorpair left;
  gmsh::model::getEntitiesInBoundingBox(-1e-6, -1e-6, -1e-6, 1e-6, 1 + 1e-6, 0.5 + 1e-6, left, 2);
  EXPECT_EQ(left.size(), 1u);
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {volume}), "body");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {left.at(0).second}), "left");
  gmsh::model::addPhysicalGroup(2, {bottom}, 7);
  gmsh::model::mesh::generate(3);
  gmsh::option::setNumber("Mesh.MshFileVersion", version);
  gmsh::option::setNumber("Mesh.Binary", binary ? 1 : 0);
  gmsh::write(path);
  gmsh::finalize();
  return path;
}

void check_block(const ImportedMesh& mesh) {
  const PointCloud& cloud = mesh.cloud;
  EXPECT_EQ(cloud.size(), 5 * 3 * 3);
  EXPECT_TRUE(mesh.has_hexahedra);
  EXPECT_NEAR(cloud.volumes.sum(), 1.0, 1e-12);
  EXPECT_GT(cloud.volumes.minCoeff(), 0.0);
  // An interior node carries a whole cell (0.5 x 0.5 x 0.25).
  for (Index i = 0; i < cloud.size(); ++i) {
    const Vec3 x = cloud.point(i);
    if (x.x() > 0.1 && x.x() < 1.9 && x.y() > 0.1 && x.y() < 0.9 && x.z() > 0.1 && x.z() < 0.4) {
      EXPECT_NEAR(cloud.volumes[i], 0.0625, 1e-14);
      EXPECT_TRUE(cloud.spacing.col(i).isApprox(Vec3(0.5, 0.5, 0.25))) << cloud.spacing.col(i).transpose();
    }
  }
  ASSERT_TRUE(cloud.sets.count("left"));
  ASSERT_TRUE(cloud.sets.count("body"));
  ASSERT_TRUE(cloud.sets.count("group7"));
  EXPECT_EQ(cloud.sets.at("left").size(), 9u);
  for (Index i : cloud.sets.at("left")) EXPECT_NEAR(cloud.positions(0, i), 0.0, 1e-12);
  EXPECT_EQ(cloud.sets.at("group7").size(), 15u);
  for (Index i : cloud.sets.at("group7")) EXPECT_NEAR(cloud.positions(2, i), 0.0, 1e-12);
  EXPECT_EQ(cloud.sets.at("body").size(), 45u);
  // Quadrilaterals of the saved faces (left 2 x 2, bottom 4 x 2) become the shell.
  EXPECT_TRUE(mesh.has_quads);
  EXPECT_EQ(mesh.shell.element_count(), 12);
  EXPECT_EQ(mesh.shell.node_count(), 9 + 15 - 3);
  EXPECT_NEAR(mesh.shell.area(), 0.5 + 2.0, 1e-12);
  ASSERT_TRUE(mesh.shell.sets.count("left"));
  EXPECT_EQ(mesh.shell.sets.at("left").size(), 9u);
  EXPECT_FALSE(mesh.shell.sets.count("body") && mesh.shell.sets.at("body").size() > 21u);
  for (Index i : mesh.shell.sets.at("left")) EXPECT_NEAR(mesh.shell.nodes(0, i), 0.0, 1e-12);
}

TEST(GmshImport, Msh41Ascii) { check_block(import_gmsh(write_block("block41.msh", 4.1, false))); }
TEST(GmshImport, Msh41Binary) { check_block(import_gmsh(write_block("block41b.msh", 4.1, true))); }
TEST(GmshImport, Msh22Ascii) { check_block(import_gmsh(write_block("block22.msh", 2.2, false))); }
TEST(GmshImport, Msh22Binary) { check_block(import_gmsh(write_block("block22b.msh", 2.2, true))); }

TEST(GmshImport, ImportTwiceInOneProcess) {
  const std::string path = write_block("twice.msh", 4.1, false);
  EXPECT_EQ(import_gmsh(path).cloud.size(), 45);
  EXPECT_EQ(import_gmsh(path).cloud.size(), 45);
}

TEST(GmshImport, HandWrittenShearedHexahedron) {
  // One affine (sheared) hexahedron 1 x 2 x 3 with a shear of the top face: volume 6,
  // each node 6/8. Node tags are not contiguous and not in order.
  const std::string path = (scratch_dir() / "sheared.msh").string();
  std::ofstream(path) << R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "clamped"
3 2 "solid"
$EndPhysicalNames
$Nodes
8
10 0 0 0
20 1 0 0
30 1 2 0
40 0 2 0
52 0.5 0.25 3
60 1.5 0.25 3
70 1.5 2.25 3
80 0.5 2.25 3
$EndNodes
$Elements
2
1 3 2 1 1 10 20 30 40
2 5 2 2 1 10 20 30 40 52 60 70 80
$EndElements
)";
  const ImportedMesh mesh = import_gmsh(path);
  ASSERT_EQ(mesh.cloud.size(), 8);
  EXPECT_EQ(mesh.node_tags.front(), 10u);
  EXPECT_EQ(mesh.node_tags.back(), 80u);
  EXPECT_TRUE(mesh.cloud.point(4).isApprox(Vec3(0.5, 0.25, 3)));
  EXPECT_NEAR(mesh.cloud.volumes.sum(), 6.0, 1e-12);
  for (Index i = 0; i < 8; ++i) EXPECT_NEAR(mesh.cloud.volumes[i], 0.75, 1e-12);
  EXPECT_EQ(mesh.cloud.sets.at("clamped"), (IndexList{0, 1, 2, 3}));
  EXPECT_EQ(mesh.cloud.sets.at("solid").size(), 8u);
  EXPECT_EQ(mesh.shell.element_count(), 1);
  EXPECT_NEAR(mesh.shell.area(), 2.0, 1e-12);
  // Through the generator interface.
  GeometrySpec spec;
  spec.type = GeometryType::mesh;
  spec.file = path;
  spec.thickness = 0.1;
  EXPECT_EQ(generate_volume_nodes(spec, {0, 0, 0}).size(), 8);
  EXPECT_DOUBLE_EQ(generate_shell_mesh(spec, {0, 0}).thickness, 0.1);
  EXPECT_NEAR(body_volume(spec), 6.0, 1e-12);
}

TEST(GmshImport, TrilinearHexahedronVolumeIsExact) {
  // A non-affine hexahedron: the unit cube with the (1,1,1) corner moved to (2,2,2). The exact
  // volume of the trilinear map is 1 + 3/4 + 1/4 + ... computed here by 4-point Gauss.
  const std::string path = (scratch_dir() / "warped.msh").string();
  std::ofstream(path) << R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 2 2 2
8 0 1 1
$EndNodes
$Elements
1
1 5 2 0 1 1 2 3 4 5 6 7 8
$EndElements
)";
  const ImportedMesh mesh = import_gmsh(path);
  ASSERT_EQ(mesh.cloud.size(), 8);
  // Reference: the volume integral with a 4-point Gauss rule (exact for the degree-2 det J).
  const double g[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  double volume = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        const double u = 0.5 * (1 + g[i]), v = 0.5 * (1 + g[j]), s = 0.5 * (1 + g[k]);
        // x = (u, v, s) + u v s (1, 1, 1): J = I + [v s, u s, u v] in every row
        Mat3 J = Mat3::Identity();
        for (int r = 0; r < 3; ++r) J.row(r) += Eigen::RowVector3d(v * s, u * s, u * v);
        volume += 0.125 * w[i] * w[j] * w[k] * J.determinant();
      }
  EXPECT_NEAR(mesh.cloud.volumes.sum(), volume, 1e-12);
  EXPECT_GT(volume, 1.0);
  EXPECT_FALSE(mesh.has_quads);
  EXPECT_TRUE(mesh.cloud.sets.empty());
}

TEST(GmshImport, MissingFileIsAnInputErrorNamingTheFile) {
  try {
    import_gmsh("/nonexistent/part.msh");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().front().key_path, "geometry.file");
    EXPECT_NE(std::string(e.what()).find("/nonexistent/part.msh"), std::string::npos);
  }
}

TEST(GmshImport, UnreadableFileIsAnInputError) {
  const std::string path = (scratch_dir() / "garbage.msh").string();
  std::ofstream(path) << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\nthis is not a mesh\n";
  try {
    import_gmsh(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().front().key_path, "geometry.file");
    EXPECT_NE(std::string(e.what()).find("garbage.msh"), std::string::npos);
  }
}

}  // namespace
}  // namespace lamina::geometry
