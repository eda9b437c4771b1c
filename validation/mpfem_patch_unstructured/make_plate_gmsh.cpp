// writes a Gmsh triangle mesh (msh 2.2 ASCII) of the plate [0,3] x [0,1.5], unstructured (Frontal-Delaunay)
#include <gmsh.h>
#include <cstdio>
int main(int argc, char** argv) {
  const double size = argc > 2 ? std::atof(argv[2]) : 0.15;
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("plate");
  const int s = gmsh::model::occ::addRectangle(0, 0, 0, 3.0, 1.5);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMin", size);
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  gmsh::option::setNumber("Mesh.Algorithm", 6);
  gmsh::model::addPhysicalGroup(2, {s}, 1);
  gmsh::model::mesh::generate(2);
  gmsh::option::setNumber("Mesh.MshFileVersion", 2.2);
  gmsh::write(argv[1]);
  std::vector<std::size_t> tags; std::vector<double> c, p;
  gmsh::model::mesh::getNodes(tags, c, p);
  std::printf("%zu nodes\n", tags.size());
  gmsh::finalize();
}
