// writes a Gmsh triangle mesh (msh 2.2 ASCII) of NAFEMS LE1: the quarter of the region between the ellipses
// (x/2)^2 + y^2 = 1 and (x/3.25)^2 + (y/2.75)^2 = 1 (Frontal-Delaunay); usage: ./a.out le1.msh size [size_at_D]
// size_at_D < size grades the mesh towards D = (2, 0) (linear in the distance, reaching size at distance 1.5)
#include <gmsh.h>
#include <cstdio>
#include <cstdlib>
int main(int argc, char** argv) {
  if (argc < 3) { std::fprintf(stderr, "usage: %s out.msh size [size_at_D]\n", argv[0]); return 2; }
  const double size = std::atof(argv[2]);
  const double size_d = argc > 3 ? std::atof(argv[3]) : size;
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("le1");
  namespace geo = gmsh::model::geo;
  const int o = geo::addPoint(0, 0, 0, size);
  const int d = geo::addPoint(2, 0, 0, size_d), a = geo::addPoint(0, 1, 0, size);
  const int c = geo::addPoint(3.25, 0, 0, size), b = geo::addPoint(0, 2.75, 0, size);
  const int bottom = geo::addLine(d, c);
  const int outer = geo::addEllipseArc(c, o, c, b);
  const int left = geo::addLine(b, a);
  const int inner = geo::addEllipseArc(a, o, d, d);
  const int loop = geo::addCurveLoop({bottom, outer, left, inner});
  const int s = geo::addPlaneSurface({loop});
  geo::synchronize();
  if (size_d < size) {
    const int dist = gmsh::model::mesh::field::add("Distance");
    gmsh::model::mesh::field::setNumbers(dist, "PointsList", {double(d)});
    const int th = gmsh::model::mesh::field::add("Threshold");
    gmsh::model::mesh::field::setNumber(th, "InField", dist);
    gmsh::model::mesh::field::setNumber(th, "SizeMin", size_d);
    gmsh::model::mesh::field::setNumber(th, "SizeMax", size);
    gmsh::model::mesh::field::setNumber(th, "DistMin", 0.0);
    gmsh::model::mesh::field::setNumber(th, "DistMax", 1.5);
    gmsh::model::mesh::field::setAsBackgroundMesh(th);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  } else {
    gmsh::option::setNumber("Mesh.MeshSizeMin", size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  }
  gmsh::option::setNumber("Mesh.Algorithm", 6);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::model::addPhysicalGroup(2, {s}, 1);
  gmsh::model::mesh::generate(2);
  gmsh::model::mesh::removeDuplicateNodes();
  gmsh::option::setNumber("Mesh.MshFileVersion", 2.2);
  gmsh::write(argv[1]);
  std::vector<std::size_t> tags; std::vector<double> co, p;
  gmsh::model::mesh::getNodes(tags, co, p);
  std::printf("%zu nodes\n", tags.size());
  gmsh::finalize();
}
