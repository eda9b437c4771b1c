// Structural pre-check of .msh files (geometry/msh_precheck): the files libgmsh 4.8 crashed on
// (fuzz/README.md G1-G3) are InputErrors naming file:line:column; valid files pass.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "geometry/gmsh_import.hpp"
#include "geometry/msh_precheck.hpp"

namespace lamina::geometry {
namespace {

namespace fs = std::filesystem;

const fs::path kSeeds = fs::path(LAMINA_SOURCE_DIR) / "fuzz" / "corpus" / "gmsh_reader";

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// `text` written to a file of this test's scratch folder.
std::string write(const std::string& name, const std::string& text) {
  static const fs::path dir = [] {
    const fs::path d = fs::path(::testing::TempDir()) / ("lamina_msh_precheck_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// The one diagnostic of the pre-check of `text` (written as `name`); "" when it passes.
std::string problem(const std::string& name, const std::string& text) {
  try {
    precheck_msh_file(write(name, text));
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics().front().key_path, "geometry.file");
    return e.what();
  }
  return "";
}

/// The hexahedron of fuzz/corpus/gmsh_reader/warped_hex22.msh with its node count changed.
std::string warped_hex(const std::string& count) {
  std::string text = read(kSeeds / "warped_hex22.msh");
  const auto at = text.find("$Nodes\n8\n");
  EXPECT_NE(at, std::string::npos);
  return text.replace(at + 7, 1, count);
}

TEST(MshPrecheck, TheFuzzSeedsPassButTheBadOnes) {
  int files = 0;
  for (const auto& f : fs::directory_iterator(kSeeds)) {
    SCOPED_TRACE(f.path().string());
    if (f.path().filename().string().rfind("bad_", 0) == 0)  // reproducers of libgmsh crashes
      EXPECT_THROW(precheck_msh_file(f.path().string()), InputError);
    else
      EXPECT_NO_THROW(precheck_msh_file(f.path().string()));
    ++files;
  }
  EXPECT_GE(files, 15);
}

TEST(MshPrecheck, G1NodeCountBelowTheNodeLinesIsAnInputErrorNotACrash) {
  // libgmsh 4.8 reads 7 nodes, the hexahedron then names node 8 and gmsh::open segfaulted.
  const std::string path = write("part.msh", warped_hex("7"));
  try {
    import_gmsh(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(std::string(e.what()), path + ":5:1: geometry.file: expected a number of nodes equal to the 8 node lines "
                                           "before $EndNodes, found '7'");
  }
  EXPECT_NE(problem("nine.msh", warped_hex("9")).find("nine.msh:5:1: geometry.file: expected a number of nodes equal to the 8"),
            std::string::npos);
}

TEST(MshPrecheck, G5ParametricNodesOfMsh2AreRefused) {
  // binary msh 2.2 $ParametricNodes whose entities libgmsh does not know: SIGSEGV in
  // GModel::_storeVerticesInEntities (fuzz/README.md, G5); the fuzzer's reproducer and the ASCII form
  const std::string g5 = (kSeeds / "bad_g5_parametric22b.msh").string();
  try {
    precheck_msh_file(g5);
    ADD_FAILURE() << "not refused";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), g5 + ":9:1: geometry.file: expected $Nodes (save the mesh without parametric "
                                           "coordinates: Gmsh's Mesh.SaveParametric = 0), found '$ParametricNodes'");
  }
  const std::string ascii = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$ParametricNodes\n1\n1 0 0 0 3 1\n$EndParametricNodes\n";
  EXPECT_NE(problem("parametric22.msh", ascii).find("parametric22.msh:4:1: geometry.file: expected $Nodes"), std::string::npos);
}

TEST(MshPrecheck, G2HugeCountsAreRefusedBeforeGmshAllocates) {
  const std::string text =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 70000000000000 1 70000000000000\n"
      "0 1 0 1\n1\n0 0 0\n$EndNodes\n";
  const std::string path = write("huge41.msh", text);
  try {
    import_gmsh(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":5:3: geometry.file: expected a number of nodes (at most the file's size, " +
                                         std::to_string(text.size()) + " bytes), found '70000000000000'");
  }
  // The same count in a binary msh 4.1 file (its 2nd size_t after "$Nodes\n").
  std::string binary = read(kSeeds / "block41b.msh");
  const auto at = binary.find("\n$Nodes\n");
  ASSERT_NE(at, std::string::npos);
  const std::uint64_t huge = 70000000000000;
  std::memcpy(&binary[at + 8 + 8], &huge, 8);
  const std::string message = problem("huge41b.msh", binary);
  EXPECT_NE(message.find("huge41b.msh: geometry.file: expected a number of nodes of at most the file's size"), std::string::npos) << message;
  EXPECT_NE(message.find("in the binary $Nodes data, found 70000000000000 (byte "), std::string::npos) << message;
}

TEST(MshPrecheck, Msh4BlocksMustAddUpAndElementsNameKnownNodes) {
  const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string nodes = "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";
  const std::string fine = head + nodes + "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
  EXPECT_EQ(problem("tri41.msh", fine), "");
  // a block of 3 nodes under a header announcing 2 (G3: Gmsh's buffer of 2 overflowed)
  EXPECT_NE(problem("sum41.msh", head + "$Nodes\n1 2 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n")
                .find("sum41.msh:5:3: geometry.file: expected a number of nodes equal to the sum over the blocks, 3, found 2"),
            std::string::npos);
  EXPECT_NE(problem("unknown41.msh", head + nodes + "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 4\n$EndElements\n")
                .find("unknown41.msh:17:7: geometry.file: expected elements of the nodes in $Nodes (a section before), found node 4"),
            std::string::npos);
  EXPECT_NE(problem("type41.msh", head + nodes + "$Elements\n1 1 1 1\n2 1 89 1\n1 1\n$EndElements\n")
                .find("type41.msh:16:1: geometry.file: expected a Gmsh element type 1-33, 36-66, 71-75, 79-83, 92-99, "
                      "118-124 or 137, found 89"),
            std::string::npos);
  EXPECT_NE(problem("names41.msh", head + "$PhysicalNames\n1\n7 1 \"bad\"\n$EndPhysicalNames\n" + nodes)
                .find("names41.msh:6:1: geometry.file: expected a physical dimension 0-3, found '7'"),
            std::string::npos);
  EXPECT_NE(problem("twice41.msh", head + "$Nodes\n1 2 1 2\n2 1 0 2\n1\n1\n0 0 0\n1 0 0\n$EndNodes\n")
                .find("twice41.msh:8:1: geometry.file: expected unique node tags, found node 1 again"),
            std::string::npos);
}

TEST(MshPrecheck, Msh2ElementsNeedTheirTypesNodesListedBefore) {
  std::string text = read(kSeeds / "warped_hex22.msh");
  EXPECT_EQ(problem("fine22.msh", text), "");
  const std::string element = "1 5 2 0 1 1 2 3 4 5 6 7 8";
  const auto at = text.find(element);
  ASSERT_NE(at, std::string::npos);
  EXPECT_NE(problem("node9.msh", std::string(text).replace(at, element.size(), "1 5 2 0 1 1 2 3 4 5 6 7 9"))
                .find("node9.msh:17:25: geometry.file: expected elements of the nodes in $Nodes (a section before), found node 9"),
            std::string::npos);
  EXPECT_NE(problem("short22.msh", std::string(text).replace(at, element.size(), "1 5 2 0 1 1 2 3 4 5 6 7"))
                .find("short22.msh:17:1: geometry.file: expected 2 tags and the 8 nodes of type 5"),
            std::string::npos);
  EXPECT_NE(problem("count22.msh", std::string(text).replace(text.find("$Elements\n1\n") + 10, 1, "2"))
                .find("count22.msh:16:1: geometry.file: expected a number of elements equal to the 1 element lines"),
            std::string::npos);
}

TEST(MshPrecheck, BinaryMsh2ElementsNameKnownNodes) {
  // block22b.msh: "$Elements\n<count>\n", then blocks of (type, count, tags) and elements
  // (number, tags, nodes), 4-byte ints; the first element's first node becomes 99999.
  std::string binary = read(kSeeds / "block22b.msh");
  const auto header = binary.find('\n', binary.find("\n$Elements\n") + 11) + 1;
  std::int32_t block[3];
  std::memcpy(block, &binary[header], sizeof block);
  const std::int32_t missing = 99999;
  std::memcpy(&binary[header + 12 + 4 * (1 + block[2])], &missing, 4);
  const std::string message = problem("node22b.msh", binary);
  EXPECT_NE(message.find("node22b.msh: geometry.file: expected elements of the nodes in $Nodes (a section before) in the "
                         "binary $Elements data, found node 99999 (byte "),
            std::string::npos)
      << message;
}

TEST(MshPrecheck, SectionsAreFoundAsGmshFindsThem) {
  // Found by gmsh_reader_fuzzer: "$Ph\0..." is, for Gmsh, a section "Ph" ended by the first line
  // continuing with "EndPh" ($EndPhysicalNames); the $Nodes after it is read (here its huge count).
  const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string text = head + std::string("$Ph\0xx\n", 7) + "$EndPhysicalNames\n$Nodes\n1 70000000000000 1 1\n";
  EXPECT_NE(problem("nul41.msh", text).find("nul41.msh:7:3: geometry.file: expected a number of nodes (at most"), std::string::npos);
  // Sections lamina does not read and Gmsh parses trusting their counts.
  EXPECT_NE(problem("periodic41.msh", head + "$Periodic\n1\n$EndPeriodic\n")
                .find("periodic41.msh:4:1: geometry.file: expected the sections of an unpartitioned mesh"),
            std::string::npos);
  // msh 2 element tags beyond physical and elementary ones: partitions, parent elements.
  std::string hex = read(kSeeds / "warped_hex22.msh");
  const std::string element = "1 5 2 0 1 1 2 3 4 5 6 7 8";
  EXPECT_NE(problem("tags22.msh", hex.replace(hex.find(element), element.size(), "1 5 4 0 1 1 9 1 2 3 4 5 6 7 8"))
                .find("tags22.msh:17:5: geometry.file: expected at most 3 element tags"),
            std::string::npos);
}

TEST(MshPrecheck, NotAMeshFileHasNoPositionSoTheCallerLocatesItAtItsKey) {
  const std::string message = problem("notes.msh", "title: not a mesh\n");
  EXPECT_NE(message.find("geometry.file: expected a Gmsh .msh file (its first line $MeshFormat), found '"), std::string::npos)
      << message;
  EXPECT_EQ(message.find("notes.msh:"), std::string::npos) << message;
  EXPECT_NE(problem("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n").find("v3.msh:2:1: geometry.file: expected msh version 2.x or 4.x"),
            std::string::npos);
}

}  // namespace
}  // namespace lamina::geometry
