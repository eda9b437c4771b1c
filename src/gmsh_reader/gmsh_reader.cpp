// The Gmsh-API half of geometry::import_gmsh, built as a module that geometry/gmsh_import.cpp loads at
// run time (dlopen): libgmsh and its ~100 libraries (OpenCASCADE, FLTK, ...) cost about 0.12 s of symbol
// lookups at every process start, so only runs that read a .msh file pay for them.
#include "geometry/gmsh_import.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <numeric>
#include <unordered_map>

#include "core/error.hpp"

namespace lamina::geometry {

namespace {

std::mutex gmsh_mutex;

/// One Gmsh API session, quiet, finalised on scope exit.
struct GmshSession {
  GmshSession() {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
  }
  ~GmshSession() {
    try {
      gmsh::finalize();
    } catch (...) {
    }
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

/// Elements of one type (fresh output vectors: Gmsh 4.8 does not reset reused ones).
struct Elements {
  std::vector<std::size_t> tags, nodes;
  std::size_t nodes_per_element() const { return tags.empty() ? 0 : nodes.size() / tags.size(); }
};
Elements elements_of_type(int type) {
  Elements e;
  gmsh::model::mesh::getElementsByType(type, e.tags, e.nodes);
  return e;
}

std::string last_gmsh_error() {
  std::string error;
  try {
    gmsh::logger::getLastError(error);
  } catch (...) {
  }
  return error;
}

/// Integrals of the 8 trilinear shape functions times |det J| over a hexahedron (Gmsh/VTK
/// node order), 2x2x2 Gauss: exact for the trilinear map.
Eigen::Matrix<Real, 8, 1> hexahedron_node_volumes(const Eigen::Matrix<Real, 3, 8>& x) {
  static const Real corner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                    {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  const Real g = 1.0 / std::sqrt(3.0);
  Eigen::Matrix<Real, 8, 1> result = Eigen::Matrix<Real, 8, 1>::Zero();
  for (Real a : {-g, g})
    for (Real b : {-g, g})
      for (Real c : {-g, g}) {
        Eigen::Matrix<Real, 8, 1> n;
        Eigen::Matrix<Real, 8, 3> dn;
        for (int k = 0; k < 8; ++k) {
          const Real sa = corner[k][0], sb = corner[k][1], sc = corner[k][2];
          n[k] = 0.125 * (1 + sa * a) * (1 + sb * b) * (1 + sc * c);
          dn(k, 0) = 0.125 * sa * (1 + sb * b) * (1 + sc * c);
          dn(k, 1) = 0.125 * sb * (1 + sa * a) * (1 + sc * c);
          dn(k, 2) = 0.125 * sc * (1 + sa * a) * (1 + sb * b);
        }
        const Mat3 jacobian = x * dn;
        result += n * std::abs(jacobian.determinant());
      }
  return result;
}

}  // namespace

ImportedMesh import_gmsh_with_gmsh_api(const std::string& path) {
  const std::string key = "geometry.file";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(key, "an existing Gmsh .msh file", "'" + path + "' (no such file)");

  std::lock_guard<std::mutex> lock(gmsh_mutex);
  GmshSession session;
  try {
    gmsh::open(path);
  } catch (...) {
    std::string why = last_gmsh_error();
    throw InputError(key, "a readable Gmsh .msh file", "'" + path + "'" + (why.empty() ? "" : ": " + why));
  }

  ImportedMesh out;
  try {
    // Nodes, sorted by tag.
    std::vector<std::size_t> tags;
    std::vector<double> coords, parametric;
    gmsh::model::mesh::getNodes(tags, coords, parametric, -1, -1, false, false);
    if (tags.empty()) throw InputError(key, "a Gmsh mesh file with nodes", "'" + path + "' has no mesh nodes");
    std::vector<std::size_t> order(tags.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return tags[a] < tags[b]; });
    std::unordered_map<std::size_t, Index> index_of;
    index_of.reserve(tags.size());
    const Index n = static_cast<Index>(tags.size());
    PointCloud& cloud = out.cloud;
    cloud.positions.resize(3, n);
    out.node_tags.resize(tags.size());
    Index count = 0;
    for (std::size_t k : order) {
      if (index_of.count(tags[k])) continue;  // a node listed twice
      index_of[tags[k]] = count;
      out.node_tags[count] = tags[k];
      cloud.positions.col(count) = Vec3(coords[3 * k], coords[3 * k + 1], coords[3 * k + 2]);
      ++count;
    }
    cloud.positions.conservativeResize(3, count);
    out.node_tags.resize(static_cast<std::size_t>(count));
    cloud.volumes = Eigen::VectorXd::Zero(count);
    cloud.spacing = Eigen::Matrix3Xd::Zero(3, count);
    cloud.counts = {0, 0, 0};
    auto node = [&](std::size_t tag) {
      auto it = index_of.find(tag);
      if (it == index_of.end()) throw InputError(key, "elements referring to existing nodes", "'" + path + "': unknown node tag " + std::to_string(tag));
      return it->second;
    };

    // Volumes from linear hexahedra and tetrahedra.
    const Elements hexahedra = elements_of_type(5);
    out.has_hexahedra = !hexahedra.tags.empty();
    for (std::size_t e = 0; e < hexahedra.tags.size(); ++e) {
      Eigen::Matrix<Real, 3, 8> x;
      std::array<Index, 8> ids{};
      for (int a = 0; a < 8; ++a) {
        ids[a] = node(hexahedra.nodes[8 * e + a]);
        x.col(a) = cloud.positions.col(ids[a]);
      }
      const Eigen::Matrix<Real, 8, 1> v = hexahedron_node_volumes(x);
      for (int a = 0; a < 8; ++a) cloud.volumes[ids[a]] += v[a];
    }
    const Elements tetrahedra = elements_of_type(4);
    for (std::size_t e = 0; e < tetrahedra.tags.size(); ++e) {
      std::array<Index, 4> ids{};
      for (int a = 0; a < 4; ++a) ids[a] = node(tetrahedra.nodes[4 * e + a]);
      Mat3 edges;
      for (int a = 0; a < 3; ++a) edges.col(a) = cloud.positions.col(ids[a + 1]) - cloud.positions.col(ids[0]);
      const Real v = std::abs(edges.determinant()) / 6.0;
      for (int a = 0; a < 4; ++a) cloud.volumes[ids[a]] += 0.25 * v;
    }

    // Spacing from the element edges.
    std::vector<int> types;
    gmsh::model::mesh::getElementTypes(types);
    std::vector<bool> on_edge(static_cast<std::size_t>(count), false);
    for (int type : types) {
      std::string name;
      int dim = 0, order_ = 0, num_nodes = 0, num_primary = 0;
      std::vector<double> local;
      gmsh::model::mesh::getElementProperties(type, name, dim, order_, num_nodes, local, num_primary);
      if (dim < 1) continue;
      std::vector<std::size_t> edge_nodes;
      gmsh::model::mesh::getElementEdgeNodes(type, edge_nodes, -1, true);
      for (std::size_t k = 0; k + 1 < edge_nodes.size(); k += 2) {
        const Index a = node(edge_nodes[k]), b = node(edge_nodes[k + 1]);
        const Vec3 d = (cloud.positions.col(a) - cloud.positions.col(b)).cwiseAbs();
        cloud.spacing.col(a) = cloud.spacing.col(a).cwiseMax(d);
        cloud.spacing.col(b) = cloud.spacing.col(b).cwiseMax(d);
        on_edge[a] = on_edge[b] = true;
      }
    }
    for (Index i = 0; i < count; ++i) {
      if (on_edge[i] || count < 2) continue;
      Real best = std::numeric_limits<Real>::infinity();
      Vec3 d = Vec3::Zero();
      for (Index j = 0; j < count; ++j) {
        if (j == i) continue;
        const Vec3 diff = cloud.positions.col(j) - cloud.positions.col(i);
        if (diff.norm() < best) {
          best = diff.norm();
          d = Vec3::Constant(best);
        }
      }
      cloud.spacing.col(i) = d;
    }

    // Triangles (linear and quadratic): their corners.
    for (int type : {2, 9}) {
      const Elements t = elements_of_type(type);
      const std::size_t per = t.nodes_per_element();
      for (std::size_t e = 0; e < t.tags.size(); ++e)
        out.triangles.push_back({node(t.nodes[per * e]), node(t.nodes[per * e + 1]), node(t.nodes[per * e + 2])});
    }

    // Quadrilaterals -> shell elements on the nodes they use.
    std::vector<std::array<Index, 4>> quads;
    for (int type : {3, 10, 16}) {
      const Elements q = elements_of_type(type);
      const std::size_t per = q.nodes_per_element();
      for (std::size_t e = 0; e < q.tags.size(); ++e)
        quads.push_back({node(q.nodes[per * e]), node(q.nodes[per * e + 1]), node(q.nodes[per * e + 2]), node(q.nodes[per * e + 3])});
    }
    out.has_quads = !quads.empty();
    std::vector<Index> shell_index(static_cast<std::size_t>(count), -1);
    for (const auto& q : quads)
      for (Index a : q) shell_index[a] = 0;
    Index shell_count = 0;
    for (Index i = 0; i < count; ++i)
      if (shell_index[i] >= 0) shell_index[i] = shell_count++;
    out.shell.nodes.resize(3, shell_count);
    for (Index i = 0; i < count; ++i)
      if (shell_index[i] >= 0) out.shell.nodes.col(shell_index[i]) = cloud.positions.col(i);
    out.shell.quads.resize(4, static_cast<Index>(quads.size()));
    for (std::size_t e = 0; e < quads.size(); ++e)
      for (int a = 0; a < 4; ++a) out.shell.quads(a, static_cast<Index>(e)) = shell_index[quads[e][a]];

    // Physical groups -> node sets.
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, -1);
    for (const auto& [dim, tag] : groups) {
      std::string name;
      gmsh::model::getPhysicalName(dim, tag, name);
      if (name.empty()) name = "group" + std::to_string(tag);
      std::vector<std::size_t> group_nodes;
      std::vector<double> group_coords;
      gmsh::model::mesh::getNodesForPhysicalGroup(dim, tag, group_nodes, group_coords);
      IndexList& set = cloud.sets[name];
      for (std::size_t t : group_nodes) set.push_back(node(t));
    }
    for (auto& [name, set] : cloud.sets) {
      std::sort(set.begin(), set.end());
      set.erase(std::unique(set.begin(), set.end()), set.end());
      IndexList shell_set;
      for (Index i : set)
        if (shell_index[i] >= 0) shell_set.push_back(shell_index[i]);
      if (!shell_set.empty()) out.shell.sets[name] = std::move(shell_set);
    }
  } catch (const InputError&) {
    throw;
  } catch (...) {
    std::string why = last_gmsh_error();
    throw InputError(key, "a readable Gmsh .msh file", "'" + path + "'" + (why.empty() ? "" : ": " + why));
  }
  return out;
}

}  // namespace lamina::geometry

/// The module's one entry point (C linkage, so dlsym finds it by this name); errors are thrown as
/// lamina::InputError, caught by the caller (same compiler and libstdc++, type compared by name).
extern "C" __attribute__((visibility("default"))) void lamina_gmsh_import(const std::string* path,
                                                                          lamina::geometry::ImportedMesh* out) {
  *out = lamina::geometry::import_gmsh_with_gmsh_api(*path);
}
