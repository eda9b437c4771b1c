#include "geometry/msh_precheck.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string_view>
#include <unordered_set>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace lamina::geometry {

namespace {

using u64 = std::uint64_t;
constexpr long long kInt = 2147483647;  // msh 2 numbers are C ints in Gmsh
const std::string kTags = "at most 3 element tags, a third one 0 (an unpartitioned mesh without parent elements)";
const std::string kTypes = "a Gmsh element type 1-33, 36-66, 71-75, 79-83, 92-99, 118-124 or 137";

/// Nodes of a Gmsh element type (MElement::getInfoMSH); 0 for the types refused here: unknown,
/// polygons / polyhedra (34, 35, 69) and the types libgmsh 4.8 cannot create from a file (84-89,
/// 100-105, 125-132; an msh 2 prism of type 89 even crashed it), measured type by type.
int nodes_of_type(long long type) {
  static constexpr int n[138] = {
      0,  2,  3,  4,   4,   8,   6,   5,   3,  6,  9,   10,  27, 18, 14, 1,  8,   20,  15, 13, 9,  10, 12, 15, 15, 21, 4,  5,
      6,  20, 35, 56,  22,  28,  0,   0,   16, 25, 36,  12,  16, 20, 28, 36, 45,  55,  66, 49, 64, 81, 100, 121, 18, 21, 24, 27,
      30, 24, 28, 32,  36,  40,  7,   8,   9,  10, 11,  0,   0,  0,  0,  84, 120, 165, 220, 286, 0, 0, 0, 34, 40, 46, 52, 58,
      0,  0,  0,  0,   0,   0,   0,   0,   64, 125, 216, 343, 512, 729, 1000, 32, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
      0,  0,  0,  0,   30,  55,  91,  140, 204, 285, 385, 0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  0,  16};
  return type >= 0 && type < 138 ? n[type] : 0;
}

struct Token {
  std::string_view text;
  std::size_t at;  // byte offset in the file
};

class Checker {
 public:
  Checker(const std::string& path, const std::string& key, std::string data) : path_(path), key_(key), s_(std::move(data)) {}

  void run() {
    std::string_view line;
    std::size_t at = 0;
    // Gmsh's readers look for $MeshFormat each in its own way (pieces of 255 or 1023 bytes, a first
    // line "?NOD" means msh 1): only a file starting with it is read alike by all of them.
    if (!next_line(line, at) || line != "$MeshFormat")
      throw InputError(key_, "a Gmsh .msh file (its first line $MeshFormat)", "'" + path_ + "'");
    const auto f = entry(3, "the format line 'version file-type data-size' (e.g. '4.1 0 8')");
    version_ = real(f[0]);
    if (!(version_ >= 2 && version_ < 3) && !(version_ >= 4 && version_ < 5)) fail(f[0].at, "msh version 2.x or 4.x", quoted(f[0].text));
    binary_ = integer(f[1], 0, 1, "file-type 0 (ASCII) or 1 (binary)") == 1;
    if ((integer(f[2], 0, 64, "a data size") != 8 || version_ < 4.1) && binary_ && version_ >= 4)
      fail(line_at_, "binary msh 4 as '4.1 1 8' (what Gmsh reads)", quoted(line_));
    if (binary_) {
      const std::uint32_t one = get<std::uint32_t>("the binary integer 1");
      swap_ = one != 1;
      if (swap_ && __builtin_bswap32(one) != 1) fail_binary("the integer 1 after the format line", std::to_string(one));
      finish_binary();
    }
    end_of("MeshFormat");
    const bool msh2 = version_ < 3;
    const std::size_t piece = msh2 ? 255 : 1023;  // Gmsh reads section lines with fgets into 256 / 1024 bytes
    bool nodes = false, elements = false;
    while (next_line(line, at, piece)) {
      if (line[0] != '$') continue;
      // Gmsh's section name: the C string after '$' (up to a NUL byte, with the line's end when it has one)
      const std::string raw(line.substr(1, line.find('\0') - 1));
      section_ = raw.substr(0, raw.find_last_not_of("\r\n") + 1);
      auto is = [&](const char* prefix) { return section_.rfind(prefix, 0) == 0; };
      if (is("MeshFormat")) fail(at, "one $MeshFormat section", "a second one");
      static const std::vector<const char*> refused2 = {"NodeData", "ElementData", "ElementNodeData", "InterpolationScheme"},
                                            refused4 = {"NodeData",      "ElementData",         "ElementNodeData", "Periodic",
                                                        "GhostElements", "PartitionedEntities", "Parametrizations"};
      for (const char* refused : msh2 ? refused2 : refused4)
        if (is(refused))
          fail(at, "the sections of an unpartitioned mesh (lamina reads nodes, elements, physical names; libgmsh trusts the counts of $" +
                       std::string(refused) + ")", quoted(line.substr(0, line.find_first_of("\r\n"))));
      // msh 2 $ParametricNodes classify nodes on model entities by tag; libgmsh 4.8 keeps a node whose
      // entity it does not know with a null entity and dies on it (SIGSEGV in _storeVerticesInEntities, G5)
      if (msh2 && is("ParametricNodes"))
        fail(at, "$Nodes (save the mesh without parametric coordinates: Gmsh's Mesh.SaveParametric = 0)",
             quoted(line.substr(0, line.find_first_of("\r\n"))));
      if (is("PhysicalNames")) {
        physical_names();
      } else if (is("Nodes") || (msh2 && is("NO"))) {
        if (std::exchange(nodes, true)) fail(at, "one $Nodes section", "a second one");
        msh2 ? nodes2() : blocks4(true);
      } else if (is("Elements") || (msh2 && is("ELM"))) {
        if (std::exchange(elements, true)) fail(at, "one $Elements section", "a second one");
        msh2 ? elements2() : blocks4(false);
      } else if (!msh2 && binary_ && is("Entities")) {
        long long counts[4];
        for (auto& c : counts) c = count64("a number of entities");
        for (int dim = 0; dim < 4; ++dim)
          for (long long i = 0; i < counts[dim]; ++i) {
            skip(1, 4 + (dim ? 48 : 24), "an entity's tag and box");
            skip(count64("a number of physical tags"), 4, "the physical tags");
            if (dim) skip(count64("a number of bounding entities"), 4, "the bounding entities");
          }
        finish_binary();
      } else {
        // not checked: skipped as Gmsh skips it. msh 2 (_readMSH2): to the next line that starts with '$',
        // which is then itself taken as a section name (so "$EndX" of an unknown $X, and whatever follows,
        // is looked at: G5 hid its $ParametricNodes behind an unknown section); msh 4: up to the first
        // piece whose [1..] starts "End" + the raw name.
        if (msh2) continue;
        const std::string end = "End" + raw;
        while (next_line(line, at, piece) && line.substr(1, end.size()) != end) {}
        continue;
      }
      end_of(section_);
    }
  }

 private:
  const std::string path_, key_, s_;
  std::size_t pos_ = 0, line_at_ = 0;  // read position; start of line_
  std::string_view line_;              // the line tokens() read last
  std::string section_;
  double version_ = 0;
  bool binary_ = false, swap_ = false;
  std::unordered_set<u64> nodes_;

  [[noreturn]] void fail(std::size_t at, const std::string& expected, const std::string& found) const {
    at = std::min(at, s_.size());
    const int line = 1 + static_cast<int>(std::count(s_.begin(), s_.begin() + static_cast<long>(at), '\n'));
    const std::size_t start = at == 0 ? 0 : s_.rfind('\n', at - 1) + 1;  // npos + 1 == 0
    throw InputError(Diagnostic{path_, line, static_cast<int>(at - start) + 1, key_, expected, found});
  }
  [[noreturn]] void fail_binary(const std::string& expected, const std::string& found) const {
    throw InputError(Diagnostic{path_, 0, 0, key_, expected + " in the binary $" + section_ + " data",
                                found + " (byte " + std::to_string(pos_) + ")"});
  }
  /// A problem with a value at `at` (ASCII) or just read (binary).
  [[noreturn]] void fail_value(std::size_t at, const std::string& expected, const std::string& found) const {
    binary_ ? fail_binary(expected, found) : fail(at, expected, found);
  }
  static std::string quoted(std::string_view text) {
    std::string q(1, '\'');  // (not "'" + std::string: a false -Wrestrict of GCC 12)
    return q.append(text.substr(0, 60)).append(text.size() > 60 ? "...'" : "'");
  }

  /// The next line (trailing white space removed); false at the end of the file. With a `piece`
  /// size: what fgets reads into a buffer of piece + 1 bytes (through '\n', at most `piece` bytes, kept raw).
  bool next_line(std::string_view& line, std::size_t& at, std::size_t piece = 0) {
    if (pos_ >= s_.size()) return false;
    at = pos_;
    const std::size_t end = std::min(s_.find('\n', pos_), s_.size() - 1) + 1;
    line = std::string_view(s_).substr(pos_, piece ? std::min(end - pos_, piece) : end - pos_);
    pos_ += line.size();
    while (!piece && !line.empty() && std::strchr(" \t\r\n\v\f", line.back())) line.remove_suffix(1);
    return true;
  }
  /// The tokens of the next non-blank line (kept in line_, line_at_; at most `longest` bytes, Gmsh's
  /// fgets buffers); the end of the file is a problem.
  std::vector<Token> tokens(const std::string& what, std::size_t longest = 255) {
    constexpr const char* blank = " \t\v\f";
    do
      if (!next_line(line_, line_at_)) fail(s_.size(), what, "the end of the file");
    while (line_.find_first_not_of(blank) == std::string_view::npos);
    if (line_.size() > longest) fail(line_at_, "a line of at most " + std::to_string(longest) + " characters", quoted(line_));
    std::vector<Token> out;
    for (std::size_t i = 0; (i = line_.find_first_not_of(blank, i)) != std::string_view::npos;) {
      const std::size_t j = std::min(line_.find_first_of(blank, i), line_.size());
      out.push_back({line_.substr(i, j - i), line_at_ + i});
      i = j;
    }
    return out;
  }
  /// The next line, which must hold `n` fields.
  std::vector<Token> entry(std::size_t n, const std::string& what, std::size_t longest = 255) {
    auto t = tokens(what, longest);
    if (t.size() != n || t[0].text[0] == '$')
      fail(line_at_, what + (n == 1 ? " alone on its line" : " (" + std::to_string(n) + " fields on one line)"), quoted(line_));
    return t;
  }
  /// ASCII: the lines up to the next '$' line (left to be read), each passed to `each`; their number.
  template <class Each>
  long long lines(Each&& each, std::size_t longest = 255) {
    for (long long n = 0;; ++n) {
      const std::size_t before = pos_;
      const auto t = tokens("$End" + section_, longest);
      if (t[0].text[0] == '$') {
        pos_ = before;
        return n;
      }
      each(t);
    }
  }
  template <class T>
  bool parse(std::string_view text, T& v) const {
    if (text.size() > 1 && text[0] == '+' && text[1] != '-') text.remove_prefix(1);
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    return ec == std::errc() && end == text.data() + text.size();
  }
  long long integer(const Token& t, long long min, long long max, const std::string& what) const {
    long long v = 0;
    if (!parse(t.text, v) || v < min || v > max) fail(t.at, what, quoted(t.text));
    return v;
  }
  long long count(const Token& t, const std::string& what) const {
    return integer(t, 0, static_cast<long long>(s_.size()), what + " (at most the file's size, " + std::to_string(s_.size()) + " bytes)");
  }
  double real(const Token& t) const {
    double v = 0;
    if (!parse(t.text, v)) fail(t.at, "a number", quoted(t.text));
    return v;
  }
  /// Binary data: a value in the file's byte order; counts; `n` items of `size` bytes skipped.
  template <class T>
  T get(const char* what) {
    if (pos_ > s_.size() || s_.size() - pos_ < sizeof(T)) fail_binary(what, "the end of the file");
    T v;
    std::memcpy(&v, s_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    if constexpr (sizeof(T) == 8) return swap_ ? __builtin_bswap64(v) : v;
    else return swap_ ? __builtin_bswap32(v) : v;
  }
  int get_int(const char* what) { return static_cast<int>(get<std::uint32_t>(what)); }
  long long count64(const std::string& what) {
    const u64 n = get<u64>(what.c_str());
    if (n > s_.size()) fail_binary(what + " of at most the file's size (" + std::to_string(s_.size()) + " bytes)", std::to_string(n));
    return static_cast<long long>(n);
  }
  void skip(u64 n, u64 size, const char* what) {
    if (n > (s_.size() - std::min(pos_, s_.size())) / size) fail_binary(std::string(what) + " within the file", "the end of the file");
    pos_ += n * size;
  }
  void finish_binary() { pos_ += pos_ < s_.size() && s_[pos_] == '\n'; }
  /// The next line must end the section `name`.
  void end_of(const std::string& name) {
    std::string_view line;
    std::size_t at = s_.size();
    if (!next_line(line, at) || (line != "$End" + name && line != "$END" + name))
      fail(at, "$End" + name + " after the entries its counts announce", at == s_.size() ? "the end of the file" : quoted(line));
  }
  void node(long long tag, std::size_t at, long long min) {
    if (tag < min) fail_value(at, "node tags >= " + std::to_string(min), std::to_string(tag));
    if (!nodes_.insert(static_cast<u64>(tag)).second) fail_value(at, "unique node tags", "node " + std::to_string(tag) + " again");
  }
  void known_node(long long tag, std::size_t at) const {
    if (!nodes_.count(static_cast<u64>(tag))) fail_value(at, "elements of the nodes in $Nodes (a section before)", "node " + std::to_string(tag));
  }

  void physical_names() {
    const auto h = entry(1, "the number of physical names");
    const long long n = lines([&](const std::vector<Token>& t) {
      if (t.size() < (version_ > 2 ? 3u : 2u)) fail(line_at_, version_ > 2 ? "'dimension tag \"name\"'" : "'tag \"name\"'", quoted(line_));
      if (version_ > 2) integer(t[0], 0, 3, "a physical dimension 0-3");
    });
    if (n != count(h[0], "a number of physical names"))
      fail(h[0].at, "a number of physical names equal to the " + std::to_string(n) + " lines that follow", quoted(h[0].text));
  }

  void nodes2() {
    const auto h = entry(1, "the number of nodes");
    const long long n = count(h[0], "a number of nodes");
    if (binary_) {
      for (long long i = 0; i < n; ++i) {
        node(get_int("a node tag"), 0, 0);
        skip(3, 8, "node coordinates");
      }
      return finish_binary();
    }
    const long long found = lines([&](const std::vector<Token>& t) {
      if (t.size() != 4) fail(line_at_, "a node line 'tag x y z'", quoted(line_));
      for (std::size_t k = 1; k < 4; ++k) real(t[k]);
      node(integer(t[0], 0, kInt, "a node tag 0-2147483647"), t[0].at, 0);
    });
    if (found != n) fail(h[0].at, "a number of nodes equal to the " + std::to_string(found) + " node lines before $EndNodes", quoted(h[0].text));
  }

  void elements2() {
    const auto h = entry(1, "the number of elements");
    const long long n = count(h[0], "a number of elements");
    if (binary_) {
      for (long long done = 0; done < n;) {
        const int type = get_int("an element type"), block = get_int("a number of elements"), tags = get_int("a number of tags");
        if (!nodes_of_type(type)) fail_binary(kTypes, std::to_string(type));
        if (block < 1 || block > n - done || tags < 0 || tags > 3)
          fail_binary("a block within the section's count", std::to_string(block) + " elements with " + std::to_string(tags) + " tags");
        for (int e = 0; e < block; ++e) {
          skip(1 + std::min(tags, 2), 4, "an element's number and tags");
          if (tags == 3 && get_int("an element's third tag") != 0) fail_binary(kTags, "another third tag");
          for (int k = 0; k < nodes_of_type(type); ++k) known_node(get_int("an element's node"), 0);
        }
        done += block;
      }
      return finish_binary();
    }
    const long long found = lines([&](const std::vector<Token>& t) {
      if (t.size() < 3) fail(line_at_, "an element line 'number type tag-count tags... nodes...'", quoted(line_));
      integer(t[0], -kInt - 1, kInt, "an element number");
      const int nn = nodes_of_type(integer(t[1], 1, 137, kTypes));
      if (!nn) fail(t[1].at, kTypes, quoted(t[1].text));
      const long long tags = integer(t[2], 0, 3, kTags);
      if (tags == 3 && t.size() > 5) integer(t[5], 0, 0, kTags);
      if (static_cast<long long>(t.size()) != 3 + tags + nn)
        fail(line_at_, std::to_string(tags) + " tags and the " + std::to_string(nn) + " nodes of type " + std::string(t[1].text), quoted(line_));
      for (std::size_t k = 3; k < t.size(); ++k) {
        const long long v = integer(t[k], -kInt - 1, kInt, "an integer tag or node");
        if (k >= 3 + static_cast<std::size_t>(tags)) known_node(v, t[k].at);
      }
    }, std::string::npos);
    if (found != n) fail(h[0].at, "a number of elements equal to the " + std::to_string(found) + " element lines before $EndElements", quoted(h[0].text));
  }

  /// msh 4 $Nodes (`nodes`) or $Elements: header 'blocks count [min-tag max-tag]', then blocks
  /// 'dimension entity parametric|type count' (4.0: 'entity dimension ...') and their entries.
  void blocks4(bool nodes) {
    const std::string what = nodes ? "a number of nodes" : "a number of elements";
    const bool v41 = version_ >= 4.1;
    long long blocks = 0, n = 0, sum = 0;
    std::size_t n_at = 0;
    if (binary_) {
      blocks = count64("a number of blocks");
      n = count64(what);
      skip(2, 8, "the minimum and maximum tag");
    } else {
      const auto h = entry(v41 ? 4 : 2, "the section's header 'blocks " + std::string(nodes ? "nodes" : "elements") + (v41 ? " min-tag max-tag'" : "'"));
      blocks = count(h[0], "a number of blocks");
      n = count(h[1], what);
      n_at = h[1].at;
    }
    for (long long b = 0; b < blocks; ++b) {
      long long dim = 0, kind = 0, m = 0;
      if (binary_) {
        dim = get_int("an entity dimension");
        skip(1, 4, "an entity tag");
        kind = get_int(nodes ? "parametric" : "an element type");
        m = count64(what);
      } else {
        const auto t = entry(4, "a block header 'dimension entity " + std::string(nodes ? "parametric" : "type") + " count'");
        dim = integer(t[v41 ? 0 : 1], 0, 3, "an entity dimension 0-3");
        kind = integer(t[2], 0, kInt, nodes ? "parametric 0 or 1" : kTypes);
        m = count(t[3], what);
      }
      if (dim < 0 || dim > 3) fail_value(line_at_, "an entity dimension 0-3", std::to_string(dim));
      if (nodes && (kind < 0 || kind > 1)) fail_value(line_at_, "parametric 0 or 1", std::to_string(kind));
      if (!nodes && !nodes_of_type(kind)) fail_value(line_at_, kTypes, std::to_string(kind));
      nodes ? node_block(dim, kind, m) : element_block(nodes_of_type(kind), m);
      sum += m;
    }
    if (sum != n) fail_value(n_at, what + " equal to the sum over the blocks, " + std::to_string(sum), std::to_string(n));
    if (binary_) finish_binary();
  }
  void node_block(long long dim, long long parametric, long long m) {
    const std::size_t coords = 3 + static_cast<std::size_t>(parametric ? dim : 0);
    if (binary_) {
      for (long long i = 0; i < m; ++i) node(static_cast<long long>(get<u64>("a node tag")), 0, 1);
      return skip(static_cast<u64>(m) * coords, 8, "node coordinates");
    }
    const bool v41 = version_ >= 4.1;  // 4.1: m tag lines, then m coordinate lines; 4.0: m lines 'tag x y z'
    for (long long i = 0; i < m; ++i) {
      const auto t = entry(v41 ? 1 : 1 + coords, v41 ? "a node tag" : "a node line 'tag x y z'");
      node(integer(t[0], 1, INT64_MAX, "a node tag >= 1"), t[0].at, 1);
      for (std::size_t k = 1; k < t.size(); ++k) real(t[k]);
    }
    for (long long i = 0; v41 && i < m; ++i)
      for (const auto& c : entry(coords, "node coordinates")) real(c);
  }
  void element_block(int nn, long long m) {
    for (long long i = 0; i < m; ++i) {
      if (binary_) {
        skip(1, 8, "an element tag");
        for (int k = 0; k < nn; ++k) known_node(static_cast<long long>(get<u64>("an element's node")), 0);
        continue;
      }
      const auto t = entry(1 + static_cast<std::size_t>(nn), "an element line 'tag' and its " + std::to_string(nn) + " nodes", 9990);
      integer(t[0], 1, INT64_MAX, "an element tag >= 1");
      for (int k = 1; k <= nn; ++k) known_node(integer(t[k], 1, INT64_MAX, "a node tag >= 1"), t[k].at);
    }
  }
};

}  // namespace

void precheck_msh_file(const std::string& path, const std::string& key) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(key, "a readable Gmsh .msh file", "'" + path + "' (cannot be opened)");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Checker(path, key, std::move(data)).run();
}

}  // namespace lamina::geometry
