// writes a Gmsh triangle mesh (msh 2.2 ASCII) of the cantilever [0, 48] x [-6, 6], unstructured (Frontal-Delaunay);
// usage: ./a.out beam_gmsh_h1.msh 1  (uniform element size)
#include <gmsh.h>
#include <cstdio>
#include <cstdlib>
int main(int argc, char** argv) {
  if (argc < 3) { std::fprintf(stderr, "usage: %s out.msh size\n", argv[0]); return 2; }
  const double size = std::atof(argv[2]);
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("beam");
  const int p1 = gmsh::model::geo::addPoint(0, -6, 0, size), p2 = gmsh::model::geo::addPoint(48, -6, 0, size);
  const int p3 = gmsh::model::geo::addPoint(48, 6, 0, size), p4 = gmsh::model::geo::addPoint(0, 6, 0, size);
  const int l1 = gmsh::model::geo::addLine(p1, p2), l2 = gmsh::model::geo::addLine(p2, p3);
  const int l3 = gmsh::model::geo::addLine(p3, p4), l4 = gmsh::model::geo::addLine(p4, p1);
  const int loop = gmsh::model::geo::addCurveLoop({l1, l2, l3, l4});
  const int s = gmsh::model::geo::addPlaneSurface({loop});
  gmsh::model::geo::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMin", size);
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  gmsh::option::setNumber("Mesh.Algorithm", 6);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::model::addPhysicalGroup(2, {s}, 1);
  gmsh::model::mesh::generate(2);
  gmsh::option::setNumber("Mesh.MshFileVersion", 2.2);
  gmsh::write(argv[1]);
  std::vector<std::size_t> tags; std::vector<double> c, p;
  gmsh::model::mesh::getNodes(tags, c, p);
  std::printf("%zu nodes\n", tags.size());
  gmsh::finalize();
}
