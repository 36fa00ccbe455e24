// Mesh file I/O. The parsers and writers here are our own rather than OpenMesh's, because
// OpenMesh 9's IO layer cannot give the guarantees mesh_io.h promises:
//  - every reader (OBJ, OFF, PLY even with "property double", ASCII STL) parses coordinates as
//    float32, and every writer converts to float32 (1e300 becomes inf, OBJ writes fixed notation
//    so 1e-20 becomes 0), so a double round trip is impossible;
//  - its importer silently repairs input: faces with an out-of-range index are dropped, repeated
//    corners removed, and faces on a non-manifold edge get duplicated vertices (the vertex count
//    changes), with only a message on omerr;
//  - a truncated OFF reads the first face line as a vertex and returns success with no faces.
// Everything below is strict instead: it either returns exactly what the file holds or throws.

#include "strata/mesh_io.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <unordered_set>

#include "internal/polygon.h"
#include "internal/read_file.h"
#include "internal/welder.h"
#include "strata/atomic_file.h"
#include "strata/exceptions.h"
#include "strata/mesh_processing.h"

namespace strata {
namespace {

constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";

namespace fs = std::filesystem;

constexpr long long kMaxIndexCount = std::numeric_limits<int>::max();  // TriMesh indexes with int

enum class Format { Obj, Off, Ply, Stl };

bool host_is_little_endian() {
  const uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

//! Loads a little-endian value (binary STL and PLY data) on any host.
template <class T>
T load_le(const char* p) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof b);
  if (!host_is_little_endian()) std::reverse(b, b + sizeof b);
  T x;
  std::memcpy(&x, b, sizeof x);
  return x;
}

[[noreturn]] void fail_io(const std::string& name, const std::string& what) {
  throw IoError(name + ": " + what);
}
[[noreturn]] void fail_input(const std::string& name, const std::string& what) {
  throw InvalidInput(name + ": " + what);
}

std::string to_lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

//! Quotes a token for a message, cut short so binary garbage cannot flood it.
std::string quote_token(std::string_view tok) {
  std::string s;
  for (char c : tok.substr(0, 40)) s += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  if (tok.size() > 40) s += "...";
  return "'" + s + "'";
}

std::string supported_list() {
  std::string s;
  for (const std::string& e : supported_mesh_extensions()) s += (s.empty() ? "" : ", ") + e;
  return s;
}

Format format_of(const std::string& path) {
  if (path.empty()) fail_io("\"\"", "an empty path names no mesh file");  // was ": no file extension"
  const std::string ext = to_lower(fs::path(path).extension().string());
  if (ext == ".obj") return Format::Obj;
  if (ext == ".off") return Format::Off;
  if (ext == ".ply") return Format::Ply;
  if (ext == ".stl") return Format::Stl;
  if (ext.empty())
    fail_io(path, "no file extension to tell the mesh format (supported: " + supported_list() + ")");
  fail_io(path, "unsupported mesh file extension '" + ext + "' (supported: " + supported_list() + ")");
}

// ---------------------------------------------------------------------------------------------
// Numbers. std::from_chars is locale-independent and exact (the double nearest to the text).

enum class Parsed { Ok, Malformed, OutOfRange };

std::string_view strip_plus(std::string_view s) {
  // from_chars rejects a leading '+', which some writers emit.
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}

Parsed parse_double(std::string_view s, double& v) {
  s = strip_plus(s);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range) return Parsed::OutOfRange;
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || s.empty()) return Parsed::Malformed;
  return Parsed::Ok;
}

Parsed parse_int(std::string_view s, long long& v) {
  s = strip_plus(s);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec == std::errc::result_out_of_range) return Parsed::OutOfRange;
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || s.empty()) return Parsed::Malformed;
  return Parsed::Ok;
}

double need_double(std::string_view tok, const std::string& name, const std::string& where) {
  double v = 0.0;
  switch (parse_double(tok, v)) {
    case Parsed::Ok:
      return v;
    case Parsed::OutOfRange:
      fail_io(name, where + ": number " + quote_token(tok) + " is out of the range of a double");
    case Parsed::Malformed:
      break;
  }
  fail_io(name, where + ": cannot parse " + quote_token(tok) + " as a number");
}

long long need_int(std::string_view tok, const std::string& name, const std::string& where) {
  long long v = 0;
  switch (parse_int(tok, v)) {
    case Parsed::Ok:
      return v;
    case Parsed::OutOfRange:
      fail_io(name, where + ": integer " + quote_token(tok) + " is out of range");
    case Parsed::Malformed:
      break;
  }
  fail_io(name, where + ": cannot parse " + quote_token(tok) + " as an integer");
}

// ---------------------------------------------------------------------------------------------
// Text scanning.

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

//! Rejects binary data in a text format: a NUL byte never occurs in a valid text mesh file.
void reject_nul_bytes(std::string_view text, const std::string& name, const char* format) {
  const size_t nul = text.find('\0');
  if (nul == std::string_view::npos) return;
  const long long line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n');
  fail_io(name, "line " + std::to_string(line) + ": contains a NUL byte; not a text " + format + " file");
}

//! Splits text into lines (without the line break) and counts them.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++line_no_;
    return true;
  }
  long long line_no() const { return line_no_; }
  //! True if the last line returned ends the text without a line break (a hint of truncation).
  bool last_line_unterminated() const { return pos_ > text_.size(); }
  std::string where() const { return "line " + std::to_string(line_no_); }
  //! Offset just after the last line returned (start of the next one).
  size_t pos() const { return std::min(pos_, text_.size()); }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  long long line_no_ = 0;
};

//! Whitespace-separated tokens of one line.
class LineTokens {
 public:
  explicit LineTokens(std::string_view line) : rest_(line) {}
  bool next(std::string_view& tok) {
    size_t i = 0;
    while (i < rest_.size() && is_blank(rest_[i])) ++i;
    if (i == rest_.size()) return false;
    size_t j = i;
    while (j < rest_.size() && !is_blank(rest_[j])) ++j;
    tok = rest_.substr(i, j - i);
    rest_ = rest_.substr(j);
    return true;
  }

 private:
  std::string_view rest_;
};

//! Cuts a line at a '#' comment (no number or keyword of OBJ/OFF contains '#').
std::string_view strip_comment(std::string_view line) {
  const size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

bool is_blank_line(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return is_blank(c); });
}

//! Whitespace-separated tokens across lines, tracking the line number for messages.
class TextCursor {
 public:
  TextCursor(std::string_view text, long long first_line) : text_(text), line_no_(first_line) {}
  bool next(std::string_view& tok) {
    skip_space();
    if (pos_ >= text_.size()) return false;
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
    tok = text_.substr(start, pos_ - start);
    return true;
  }
  void skip_rest_of_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }
  bool at_end() {
    skip_space();
    return pos_ >= text_.size();
  }
  std::string where() const { return "line " + std::to_string(line_no_); }

 private:
  void skip_space() {
    while (pos_ < text_.size() && (is_blank(text_[pos_]) || text_[pos_] == '\n')) {
      if (text_[pos_] == '\n') ++line_no_;
      ++pos_;
    }
  }
  std::string_view text_;
  size_t pos_ = 0;
  long long line_no_;
};

// ---------------------------------------------------------------------------------------------
// Face assembly: checks each polygon against the vertex count as it is read and splits polygons
// into triangles, keeping file order. Polygons with more than three corners are triangulated at
// the end, when all positions are known (OBJ and PLY may list faces before vertices).

using Polygons = std::vector<std::vector<int>>;

//! What a reader records of the file's faces besides the triangles.
struct FaceRecord {
  Polygons* polygons = nullptr;  //!< if given, every polygon as listed (before triangulation)
  //! Each polygon of more than 3 corners: its first triangle and its corner count, so that
  //! messages can name the file's face of a triangle.
  struct Cut {
    size_t first_face, n;
  };
  std::vector<Cut> cuts;
  //! If given, the per-vertex colours and texture coordinates the file holds, and notes on the
  //! data of that kind that could not be kept (read_mesh_file()).
  MeshAttributes* attributes = nullptr;
  std::vector<std::string>* dropped = nullptr;
};

//! "1st", "2nd", "3rd", "4th", .., "11th", .., "21st" for \p n >= 1.
std::string ordinal(size_t n) {
  const size_t tens = n % 100;
  const char* suffix = tens >= 11 && tens <= 13 ? "th"
                       : n % 10 == 1            ? "st"
                       : n % 10 == 2            ? "nd"
                       : n % 10 == 3            ? "rd"
                                                : "th";
  return std::to_string(n) + suffix;
}

class FaceBuilder {
 public:
  //! \param index_base added to 0-based indices when quoting them (1 for OBJ).
  //! \param record if given, receives the polygons as listed and which were cut (FaceRecord).
  FaceBuilder(const std::string& name, long long num_vertices, int index_base, FaceRecord* record = nullptr)
      : name_(name), num_vertices_(num_vertices), index_base_(index_base), record_(record) {}

  //! Adds one polygon with 0-based corner indices; \p where() names it in messages.
  //! \throw InvalidInput for fewer than 3 corners, an index out of range or a repeated index.
  template <class Where>
  void add_checked(const std::vector<long long>& c, const Where& where) {
    const size_t n = c.size();
    if (n < 3)
      fail_input(name_, where() + ": face has " + std::to_string(n) + (n == 1 ? " corner" : " corners") +
                            " (a face needs at least 3)");
    for (long long i : c)
      if (i < 0 || i >= num_vertices_)
        fail_input(name_, where() + ": face has vertex index " + std::to_string(i + index_base_) +
                              " out of range (file has " + std::to_string(num_vertices_) + " vertices)");
    if (n == 3) {
      if (c[0] == c[1] || c[0] == c[2] || c[1] == c[2])
        fail_input(name_, where() + ": face repeats vertex index " +
                              std::to_string((c[0] == c[1] || c[0] == c[2] ? c[0] : c[1]) + index_base_));
    } else {
      sorted_.assign(c.begin(), c.end());
      std::sort(sorted_.begin(), sorted_.end());
      const auto dup = std::adjacent_find(sorted_.begin(), sorted_.end());
      if (dup != sorted_.end())
        fail_input(name_, where() + ": face repeats vertex index " + std::to_string(*dup + index_base_));
    }
    if (static_cast<long long>(faces_.size()) + static_cast<long long>(n - 2) > kMaxIndexCount)
      fail_io(name_, "too many faces (more than " + std::to_string(kMaxIndexCount) + ")");
    if (record_ && record_->polygons) record_->polygons->emplace_back(c.begin(), c.end());
    if (n == 3) {
      faces_.push_back({static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2])});
      return;
    }
    if (record_) record_->cuts.push_back({faces_.size(), n});
    pending_.push_back({faces_.size(), pending_corners_.size(), n});
    for (long long i : c) pending_corners_.push_back(static_cast<int>(i));
    faces_.resize(faces_.size() + n - 2);  // placeholders, filled in finish()
  }

  //! Triangulates the pending polygons and returns all faces in file order.
  //! \throw InvalidInput for a polygon that has no triangulation without overlaps found (it
  //!        crosses itself, or is nearly degenerate).
  std::vector<Face> finish(const std::vector<Vec3>& vertices);

 private:
  struct Pending {
    size_t first_face, first_corner, n;
  };
  std::string name_;
  long long num_vertices_;
  int index_base_;
  FaceRecord* record_;
  std::vector<Face> faces_;
  std::vector<Pending> pending_;
  std::vector<int> pending_corners_;
  std::vector<long long> sorted_;
};

std::vector<Face> FaceBuilder::finish(const std::vector<Vec3>& vertices) {
  // The diagonal of the faces' vertices, that validation's zero area is relative to (a vertex in
  // no face is left out: far away, it would make every ear a sliver).
  double diagonal = 0.0;
  if (!pending_.empty()) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    auto add = [&](int v) {
      lo = lo.cwiseMin(vertices[v]);
      hi = hi.cwiseMax(vertices[v]);
    };
    for (int v : pending_corners_) add(v);
    size_t next = 0;  // the next pending polygon, whose placeholders are skipped
    for (size_t f = 0; f < faces_.size(); ++f) {
      if (next < pending_.size() && f == pending_[next].first_face) {
        f += pending_[next++].n - 3;
        continue;
      }
      for (int v : faces_[f]) add(v);
    }
    diagonal = (hi - lo).stableNorm();
  }
  size_t extra = 0;  // triangles beyond one per file face, of the polygons before
  for (const Pending& p : pending_) {
    if (!internal::triangulate_polygon(vertices, pending_corners_.data() + p.first_corner, p.n, diagonal,
                                       faces_.data() + p.first_face))
      fail_input(name_, "the file's " + ordinal(p.first_face - extra + 1) + " face, a polygon of " +
                            std::to_string(p.n) +
                            " corners, has no triangulation without overlapping triangles that the reader "
                            "finds: it crosses itself, or is nearly degenerate");
    extra += p.n - 3;
  }
  pending_.clear();
  pending_corners_.clear();
  return std::move(faces_);
}

void check_vertex_count(long long n, const std::string& name) {
  if (n > kMaxIndexCount)
    fail_io(name, "too many vertices (more than " + std::to_string(kMaxIndexCount) + ")");
}

// ---------------------------------------------------------------------------------------------
// OBJ. Only 'v' and 'f' lines matter; other statements (vt, vn, g, usemtl, ...) are skipped.
// OBJ has no element counts, so truncation at a line boundary is only detectable through the
// "# N vertices, M faces" comment that write_mesh (and OpenMesh) put at the top.

struct ObjCountComment {
  bool present = false;
  long long vertices = 0, faces = 0;
  long long line = 0;
};

//! Recognizes exactly "# <N> vertices, <M> faces".
bool parse_obj_count_comment(std::string_view line, ObjCountComment& out) {
  LineTokens t(line);
  std::string_view hash, n, vw, m, fw, extra;
  if (!t.next(hash) || hash != "#" || !t.next(n) || !t.next(vw) || vw != "vertices," || !t.next(m) ||
      !t.next(fw) || fw != "faces" || t.next(extra))
    return false;
  out.present = parse_int(n, out.vertices) == Parsed::Ok && parse_int(m, out.faces) == Parsed::Ok &&
                out.vertices >= 0 && out.faces >= 0;
  return out.present;
}

// The polygons of a file as its reader saw them, in file order: poly_sizes[p] corners each, their
// vertices back to back in poly_vertices. Polygon p became poly_sizes[p] - 2 consecutive
// triangles of its corners (FaceBuilder). Returns, per triangle, each corner's offset in
// poly_vertices (found by its vertex through a map reset per polygon: linear in the corners, where
// a search of each triangle's polygon took 3.7 s for one polygon of 100k corners, review).
std::vector<std::array<int, 3>> triangle_corner_offsets(const std::vector<Face>& triangles,
                                                        std::size_t num_vertices,
                                                        const std::vector<int>& poly_sizes,
                                                        const std::vector<int>& poly_vertices) {
  std::vector<std::array<int, 3>> out(triangles.size(), {0, 0, 0});
  std::vector<int> at(num_vertices, -1);
  std::size_t tri = 0, corner = 0;
  for (const int n : poly_sizes) {
    for (int q = n - 1; q >= 0; --q)
      at[static_cast<std::size_t>(poly_vertices[corner + q])] = static_cast<int>(corner) + q;
    for (int k = 0; k + 2 < n && tri < triangles.size(); ++k, ++tri)
      for (int c = 0; c < 3; ++c) out[tri][c] = std::max(0, at[static_cast<std::size_t>(triangles[tri][c])]);
    for (int q = 0; q < n; ++q) at[static_cast<std::size_t>(poly_vertices[corner + q])] = -1;
    corner += static_cast<std::size_t>(n);
  }
  return out;
}

// Per triangle, the index of the polygon it was cut from (polygons as in
// triangle_corner_offsets()): a per-polygon value (a material, an image) goes to each.
std::vector<int> triangle_polygons(std::size_t num_triangles, const std::vector<int>& poly_sizes) {
  std::vector<int> out;
  out.reserve(num_triangles);
  for (std::size_t p = 0; p < poly_sizes.size(); ++p)
    for (int k = 0; k + 2 < poly_sizes[p] && out.size() < num_triangles; ++k)
      out.push_back(static_cast<int>(p));
  out.resize(num_triangles, 0);
  return out;
}

//! The statements of an OBJ file: its lines with '#' comments cut, and a line that ends in '\'
//! joined with the next one (the spec's line continuation; a '\' in a comment continues nothing).
//! Messages name the line a statement starts on.
class ObjStatements {
 public:
  explicit ObjStatements(std::string_view text) : lines_(text) {}
  bool next(std::string_view& statement) {
    std::string_view raw;
    if (!lines_.next(raw)) return false;
    first_line_ = lines_.line_no();
    first_raw_ = raw;
    std::string_view s = strip_comment(raw);
    if (!continued(s)) {
      statement = s;
      return true;
    }
    joined_.assign(s.data(), s.size());
    // A last line ending in '\' continues into nothing: the statement ends there.
    while (lines_.next(raw)) {
      s = strip_comment(raw);
      const bool more = continued(s);
      joined_ += ' ';  // in place of the '\', so that the lines' last and first words stay apart
      joined_.append(s.data(), s.size());
      if (!more) break;
    }
    statement = joined_;
    return true;
  }
  //! The statement's first line as it is (comment and all).
  std::string_view first_raw() const { return first_raw_; }
  long long line_no() const { return first_line_; }
  std::string where() const { return "line " + std::to_string(first_line_); }
  bool last_line_unterminated() const { return lines_.last_line_unterminated(); }

 private:
  //! Whether \p s ends in a '\' (blanks after it allowed); if so, cuts it off.
  static bool continued(std::string_view& s) {
    std::string_view t = s;
    while (!t.empty() && is_blank(t.back())) t.remove_suffix(1);
    if (t.empty() || t.back() != '\\') return false;
    t.remove_suffix(1);
    s = t;
    return true;
  }
  LineReader lines_;
  std::string_view first_raw_;
  std::string joined_;
  long long first_line_ = 0;
};

TriMesh read_obj(const std::string& name, std::string_view text, FaceRecord* record) {
  reject_nul_bytes(text, name, "OBJ");
  TriMesh mesh;
  ObjCountComment declared;
  long long face_lines = 0;
  bool seen_data = false;
  const bool want_attributes = record && record->attributes;
  std::vector<std::array<double, 4>> colors;  // up to the last coloured vertex
  long long colored = 0;
  bool alpha = false;
  std::vector<std::array<double, 2>> texcoords;  // the vt lines

  // Pass 1: vertices (and counts), so faces can refer to vertices defined later in the file.
  {
    ObjStatements lines(text);
    std::string_view statement;
    while (lines.next(statement)) {
      if (!seen_data && !declared.present && parse_obj_count_comment(lines.first_raw(), declared))
        declared.line = lines.line_no();
      LineTokens tok(statement);
      std::string_view key;
      if (!tok.next(key)) continue;
      seen_data = true;
      if (key == "f") {
        ++face_lines;
      } else if (key == "v") {
        Vec3 p;
        for (int k = 0; k < 3; ++k) {
          std::string_view s;
          if (!tok.next(s))
            fail_io(name, lines.where() + ": vertex has " + std::to_string(k) + " coordinates, needs 3" +
                              (lines.last_line_unterminated() ? " (file truncated?)" : ""));
          p[k] = need_double(s, name, lines.where());
        }
        check_vertex_count(static_cast<long long>(mesh.vertices.size()) + 1, name);
        mesh.vertices.push_back(p);
        if (want_attributes) {
          // Three or four more numbers are a colour ("v x y z r g b [a]", as MeshLab writes it);
          // one is the rational weight w, ignored as before.
          std::array<double, 4> c{0.0, 0.0, 0.0, 1.0};
          int n = 0;
          std::string_view s;
          bool numbers = true;
          while (tok.next(s)) {
            if (n < 4) numbers = numbers && parse_double(s, c[n]) == Parsed::Ok;
            ++n;
          }
          if (numbers && (n == 3 || n == 4)) {
            if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]) || !std::isfinite(c[3]))
              fail_input(name, lines.where() + ": vertex " + std::to_string(mesh.vertices.size() - 1) +
                                   " has a non-finite colour");
            colors.resize(mesh.vertices.size() - 1, {0.0, 0.0, 0.0, 1.0});
            colors.push_back(c);
            ++colored;
            alpha = alpha || n == 4;
          }
        }
      } else if (key == "vt" && want_attributes) {
        std::array<double, 2> uv{0.0, 0.0};
        std::string_view s;
        if (!tok.next(s)) fail_io(name, lines.where() + ": texture coordinate has no values");
        uv[0] = need_double(s, name, lines.where());
        if (tok.next(s)) uv[1] = need_double(s, name, lines.where());
        texcoords.push_back(uv);
      }
    }
  }
  // A file whose count comment says it was written whole ends with a line break: a last line
  // cut short ("f 2/2 3/3 4/1" of "... 4/12") would read as another valid line.
  if (declared.present && !text.empty() && text.back() != '\n')
    fail_io(name, "truncated: the last line has no line break, and the header comment (line " +
                      std::to_string(declared.line) + ") says the file was written whole");
  if (declared.present && (declared.vertices != mesh.num_vertices() || declared.faces != face_lines)) {
    const bool fewer = declared.vertices >= mesh.num_vertices() && declared.faces >= face_lines;
    fail_io(name, std::string(fewer ? "truncated: " : "") + "header comment (line " +
                      std::to_string(declared.line) + ") declares " + std::to_string(declared.vertices) +
                      " vertices and " + std::to_string(declared.faces) + " faces, file holds " +
                      std::to_string(mesh.num_vertices()) + " vertices and " + std::to_string(face_lines) +
                      " faces" + (fewer ? "" : " (stale comment? remove it if the file is intended)"));
  }

  // Pass 2: faces. Negative indices count back from the last vertex defined before the line.
  FaceBuilder faces(name, mesh.num_vertices(), 1, record);
  std::vector<long long> corners;
  ObjStatements lines(text);
  std::string_view statement;
  long long vertices_so_far = 0, texcoords_so_far = 0;
  // Per vertex, the vt its corners use (-1: none yet); corners with and without one; vertices
  // whose corners use different texture coordinates (seams).
  std::vector<long long> vt_of(want_attributes && !texcoords.empty() ? mesh.vertices.size() : 0, -1);
  long long corners_with_vt = 0, corners_without_vt = 0;
  bool vt_by_index = true;  // every corner uses the vt of its vertex's number (as write_mesh writes)
  std::vector<char> seam(vt_of.size(), 0);
  // Per polygon, in file order: its corners' vertices and vt (-1: none), and its material.
  std::vector<int> poly_sizes, poly_vertices, poly_vts, poly_materials;
  std::vector<std::string> material_names;
  std::unordered_map<std::string, int> material_index;
  std::string material_library;
  bool materials_seen = false;
  int material = -1;
  // The rest of a line's tokens, joined by single spaces (a material or library name).
  auto rest_of_line = [](LineTokens& t) {
    std::string out;
    std::string_view w;
    while (t.next(w)) out += (out.empty() ? "" : " ") + std::string(w);
    return out;
  };
  while (lines.next(statement)) {
    LineTokens tok(statement);
    std::string_view key;
    if (!tok.next(key)) continue;
    if (key == "v") {
      ++vertices_so_far;
      continue;
    }
    if (key == "vt") {
      ++texcoords_so_far;
      continue;
    }
    if (want_attributes && key == "mtllib") {
      const std::string lib = rest_of_line(tok);
      if (material_library.empty())
        material_library = lib;
      else if (lib != material_library)
        record->dropped->push_back("material library '" + lib + "' (" + lines.where() +
                                   "): only the first, '" + material_library + "', is kept");
      materials_seen = true;
      continue;
    }
    if (want_attributes && key == "usemtl") {
      const std::string m = rest_of_line(tok);
      materials_seen = true;
      if (m.empty()) {
        material = -1;
      } else {
        const auto [it, fresh] = material_index.emplace(m, static_cast<int>(material_names.size()));
        if (fresh) material_names.push_back(m);
        material = it->second;
      }
      continue;
    }
    if (key != "f") continue;
    corners.clear();
    const std::size_t poly_start = poly_vts.size();
    std::string_view corner;
    while (tok.next(corner)) {
      const std::size_t slash = corner.find('/');
      const std::string_view index_text = corner.substr(0, slash);  // "i", "i/t", "i//n", "i/t/n"
      if (!vt_of.empty()) {
        std::string_view t = slash == std::string_view::npos ? std::string_view() : corner.substr(slash + 1);
        t = t.substr(0, t.find('/'));
        long long ti = 0;
        if (t.empty()) {
          ++corners_without_vt;
          poly_vts.push_back(-1);
        } else if (parse_int(t, ti) != Parsed::Ok || ti == 0 ||
                   ti > static_cast<long long>(texcoords.size()) || -ti > texcoords_so_far) {
          // As vertex indices: positive ones count from the file's first vt (which may follow the
          // face), negative ones back from the last vt before the face.
          fail_input(name, lines.where() + ": face corner " + quote_token(corner) +
                               " has a texture coordinate index out of range (" +
                               (ti < 0 ? std::to_string(texcoords_so_far) + " precede it"
                                       : "the file has " + std::to_string(texcoords.size())) +
                               ")");
        } else {
          ++corners_with_vt;
          ti = ti > 0 ? ti - 1 : texcoords_so_far + ti;
          poly_vts.push_back(static_cast<int>(ti));
          long long vi = 0;
          if (parse_int(index_text, vi) == Parsed::Ok && vi != 0) {
            vi = vi > 0 ? vi - 1 : vertices_so_far + vi;
            vt_by_index = vt_by_index && vi == ti;
            if (vi >= 0 && vi < static_cast<long long>(vt_of.size())) {
              long long& mine = vt_of[static_cast<std::size_t>(vi)];
              if (mine < 0)
                mine = ti;
              else if (mine != ti &&
                       texcoords[static_cast<std::size_t>(mine)] != texcoords[static_cast<std::size_t>(ti)])
                seam[static_cast<std::size_t>(vi)] = 1;
            }
          }
        }
      }
      long long i = 0;
      if (parse_int(index_text, i) != Parsed::Ok)
        fail_io(name, lines.where() + ": cannot parse face corner " + quote_token(corner) +
                          " (expected a vertex index)");
      if (i == 0) fail_input(name, lines.where() + ": face has vertex index 0 (OBJ indices start at 1)");
      if (i < 0) {
        if (-i > vertices_so_far)
          fail_input(name, lines.where() + ": face has relative vertex index " + std::to_string(i) +
                               " but only " + std::to_string(vertices_so_far) + " vertices precede it");
        corners.push_back(vertices_so_far + i);
      } else {
        corners.push_back(i - 1);
      }
    }
    faces.add_checked(corners, [&] { return lines.where(); });
    if (want_attributes) {
      poly_sizes.push_back(static_cast<int>(corners.size()));
      for (long long c : corners) poly_vertices.push_back(static_cast<int>(c));
      if (vt_of.empty()) poly_vts.resize(poly_start + corners.size(), -1);
      poly_materials.push_back(material);
    }
  }
  mesh.faces = faces.finish(mesh.vertices);
  if (want_attributes) {
    MeshAttributes& a = *record->attributes;
    const long long nv = mesh.num_vertices();
    if (colored == nv && nv > 0) {
      a.colors = std::move(colors);
      a.colors_have_alpha = alpha;
    } else if (colored > 0) {
      record->dropped->push_back("vertex colours: only " + std::to_string(colored) + " of the " +
                                 std::to_string(nv) + " vertices have one");
    }
    const long long seams = std::count(seam.begin(), seam.end(), 1);
    if (corners_with_vt > 0 && corners_without_vt > 0) {
      record->dropped->push_back("texture coordinates: " + std::to_string(corners_without_vt) + " of the " +
                                 std::to_string(corners_with_vt + corners_without_vt) +
                                 " face corners have none");
    } else if (seams > 0) {
      // Per face corner: the file's vt list, each triangle corner's entry by its vertex.
      a.corner_uv = std::move(texcoords);
      a.corner_uv_index =
          triangle_corner_offsets(mesh.faces, mesh.vertices.size(), poly_sizes, poly_vertices);
      for (auto& t : a.corner_uv_index)
        for (int& c : t) c = poly_vts[static_cast<std::size_t>(c)];
    } else if (corners_with_vt > 0 && vt_by_index && texcoords.size() == mesh.vertices.size()) {
      a.texcoords = std::move(texcoords);  // vertices in no face keep theirs too
    } else if (corners_with_vt > 0) {
      a.texcoords.assign(mesh.vertices.size(), {0.0, 0.0});  // (0, 0) for vertices in no face
      for (std::size_t v = 0; v < vt_of.size(); ++v)
        if (vt_of[v] >= 0) a.texcoords[v] = texcoords[static_cast<std::size_t>(vt_of[v])];
    }
    if (materials_seen) {
      a.material_library = std::move(material_library);
      a.material_names = std::move(material_names);
      a.face_materials.clear();
      for (int p : triangle_polygons(mesh.faces.size(), poly_sizes))
        a.face_materials.push_back(poly_materials[p]);
    }
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OFF (ASCII; optional ST/C/N prefixes: vertex colours and texture coordinates are kept, normals
// ignored); '#' starts a comment.

//! The vertex and face records of an OFF body, read as a token stream. OFF is free-form, but its
//! writers put a record on a line of its own, followed there by its optional fields (a vertex's
//! normal, colour and texture coordinates; a face's colour), whose number the reader cannot know
//! beforehand. So a record's required values (3 coordinates; a corner count and the corners) run
//! over as many lines as they need, and the numbers after them on the line where they end are the
//! record's optional fields; only when the data lines left are too few to give every record still
//! to come a line of its own, and those numbers are whole records without optional fields
//! (vertices of a plain OFF, faces of at least 3 corners), perhaps followed by the start of one
//! more that runs on over the next lines, are they those records instead. A file of one record
//! per line thus reads as it always did.
class OffRecords {
 public:
  //! \p lines is just after the counts; \p shared_vertices: whether vertex records may share a
  //! line (a prefix C, N or ST gives them values after their positions).
  OffRecords(LineReader& lines, long long num_vertices, long long num_faces, bool shared_vertices)
      : lines_(lines),
        nv_(num_vertices),
        total_(num_vertices + num_faces),
        shared_vertices_(shared_vertices) {
    LineReader scan = lines;
    std::string_view raw;
    while (scan.next(raw)) lines_left_ += !is_blank_line(strip_comment(raw));
  }
  //! Starts record \p r (the vertices', then the faces'): false at the end of the data.
  bool start(long long r) {
    record_ = r;
    if (shared_ > 0)
      --shared_;
    else if (!next_line())
      return false;
    start_line_ = lines_.line_no();
    return true;
  }
  //! The record's next required value: false at the end of the data.
  bool need(std::string_view& tok) {
    while (!tokens_.next(tok))
      if (!next_line()) return false;
    return true;
  }
  //! Ends the record: \p optional gets its optional fields (none if the line's rest is records).
  void finish(std::vector<std::string_view>& optional) {
    optional.clear();
    if (shared_ > 0) return;  // records follow it on its line: it has no optional fields
    if (lines_left_ < total_ - record_ - 1) {
      shared_ = line_records(tokens_, record_ + 1);
      if (shared_ > 0) return;
    }
    std::string_view tok;
    while (tokens_.next(tok)) optional.push_back(tok);
  }
  //! Whether data follows the last record (where() names its line then).
  bool more() {
    LineTokens rest = tokens_;
    std::string_view tok;
    return rest.next(tok) || next_line();
  }
  //! The line being read.
  std::string where() const { return lines_.where(); }
  //! The line the record started on.
  std::string start_where() const { return "line " + std::to_string(start_line_); }

 private:
  bool next_line() {
    std::string_view raw;
    while (lines_.next(raw)) {
      const std::string_view line = strip_comment(raw);
      if (is_blank_line(line)) continue;
      tokens_ = LineTokens(line);
      --lines_left_;
      return true;
    }
    return false;
  }
  //! How many records from record \p r on \p t holds, all without optional fields, the last
  //! perhaps cut short by the line's end (it runs on over the next lines); 0 if \p t holds
  //! anything else, or no whole record.
  long long line_records(LineTokens t, long long r) const {
    long long whole = 0;
    std::string_view tok;
    for (; t.next(tok); ++r) {
      const bool vertex = r < nv_;
      double x = 0.0;
      long long values = 2, i = 0;  // after the first
      if (vertex ? !shared_vertices_ || parse_double(tok, x) != Parsed::Ok
                 : parse_int(tok, values) != Parsed::Ok || values < 3)
        return 0;
      long long got = 0;
      for (; got < values && t.next(tok); ++got)
        if ((vertex ? parse_double(tok, x) : parse_int(tok, i)) != Parsed::Ok) return 0;
      if (got < values) return whole > 0 ? whole + 1 : 0;
      ++whole;
    }
    return whole;
  }

  LineReader& lines_;
  long long nv_, total_;
  bool shared_vertices_;
  LineTokens tokens_{std::string_view()};
  long long lines_left_ = 0;  // data lines not yet started
  long long record_ = 0, start_line_ = 0;
  long long shared_ = 0;  // records left on the line being read (the last may run on)
};

TriMesh read_off(const std::string& name, std::string_view text, FaceRecord* record) {
  reject_nul_bytes(text, name, "OFF");
  LineReader lines(text);
  std::string_view raw;
  auto next_data_line = [&](std::string_view& line) {
    while (lines.next(raw)) {
      line = strip_comment(raw);
      if (!is_blank_line(line)) return true;
    }
    return false;
  };

  std::string_view line;
  if (!next_data_line(line)) fail_io(name, "empty file, expected an OFF header");
  LineTokens header(line);
  std::string_view magic;
  header.next(magic);
  bool has_st = false, has_color = false, has_normal = false;
  {
    // [ST][C][N][4][n]OFF
    std::string_view m = magic;
    if (m.substr(0, 2) == "ST") m.remove_prefix(2), has_st = true;
    if (!m.empty() && m[0] == 'C') m.remove_prefix(1), has_color = true;
    if (!m.empty() && m[0] == 'N') m.remove_prefix(1), has_normal = true;
    if (!m.empty() && (m[0] == '4' || m[0] == 'n'))
      fail_io(name, "OFF variant " + quote_token(magic) + " (not 3-dimensional) is not supported");
    if (m != "OFF")
      fail_io(name, "not an OFF file: first line starts with " + quote_token(magic) + ", expected 'OFF'");
  }
  std::array<long long, 3> counts{0, 0, 0};
  int num_counts = 0;
  std::string_view tok;
  if (header.next(tok)) {
    if (tok == "BINARY") fail_io(name, "binary OFF is not supported");
    counts[num_counts++] = need_int(tok, name, lines.where());
  }
  if (num_counts == 0) {
    if (!next_data_line(line)) fail_io(name, "truncated: no vertex and face counts after the OFF header");
    header = LineTokens(line);
  }
  while (header.next(tok)) {
    if (num_counts == 3) fail_io(name, lines.where() + ": too many numbers in the OFF counts line");
    counts[num_counts++] = need_int(tok, name, lines.where());
  }
  if (num_counts < 2) fail_io(name, lines.where() + ": expected vertex and face counts");
  const long long nv = counts[0], nf = counts[1];
  if (nv < 0 || nf < 0) fail_io(name, lines.where() + ": negative element count");
  check_vertex_count(nv, name);
  if (nf > kMaxIndexCount) fail_io(name, lines.where() + ": face count " + std::to_string(nf) + " too large");

  TriMesh mesh;
  // The values after a vertex's position: [nx ny nz] [r g b [a]] [s t]. A colour of integers is
  // on a 0-255 scale, one of floats on 0-1 (Geomview's OFF); a single value (a colour map index)
  // or another count cannot be kept, nor can texture coordinates missing on a vertex.
  const bool want_attributes = record && record->attributes;
  std::vector<std::array<double, 4>> colors;
  std::vector<std::array<double, 2>> texcoords;
  bool alpha = false, colors_ok = true, texcoords_ok = true;
  std::string color_problem, st_problem;
  auto read_off_vertex_extras = [&](const std::vector<std::string_view>& extra, long long v,
                                    const std::string& where) {
    std::size_t first = has_normal ? 3 : 0;
    std::size_t end = extra.size();
    if (has_st) {
      if (end < first + 2) {
        if (texcoords_ok)
          st_problem = "vertex " + std::to_string(v) + " has " +
                       std::to_string(end > first ? end - first : 0) + " values after its position" +
                       (has_normal ? " and normal" : "") + ", not the 2 of ST";
        texcoords_ok = false;
      } else {
        texcoords.push_back(
            {need_double(extra[end - 2], name, where), need_double(extra[end - 1], name, where)});
        end -= 2;
      }
    }
    if (!has_color || !colors_ok) return;
    const std::size_t n = end > first ? end - first : 0;
    if (n != 3 && n != 4) {
      color_problem = "vertex " + std::to_string(v) + " has " + std::to_string(n) +
                      (n == 1 ? " colour value (a colour map index)" : " colour values") + ", not 3 or 4";
      colors_ok = false;
      return;
    }
    std::array<double, 4> c{0.0, 0.0, 0.0, 1.0};
    bool integers = true;
    for (std::size_t k = 0; k < n; ++k) {
      long long i = 0;
      integers = integers && parse_int(extra[first + k], i) == Parsed::Ok;
    }
    for (std::size_t k = 0; k < n; ++k) {
      c[k] = need_double(extra[first + k], name, where);
      if (integers) c[k] /= 255.0;
    }
    colors.push_back(c);
    alpha = alpha || n == 4;
  };
  OffRecords records(lines, nv, nf, !has_color && !has_normal && !has_st);
  std::vector<std::string_view> extra;
  // Each vertex needs at least 6 bytes of text; never trust a header count for allocation.
  mesh.vertices.reserve(
      static_cast<size_t>(std::min<long long>(nv, static_cast<long long>(text.size() / 6))));
  for (long long v = 0; v < nv; ++v) {
    if (!records.start(v))
      fail_io(name, "truncated: header declares " + std::to_string(nv) + " vertices, file holds " +
                        std::to_string(v));
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      if (!records.need(tok))
        fail_io(name, records.start_where() + ": vertex " + std::to_string(v) + " has " + std::to_string(k) +
                          " coordinates, needs 3 (file truncated?)");
      p[k] = need_double(tok, name, records.where());
    }
    mesh.vertices.push_back(p);
    records.finish(extra);
    if (want_attributes && (has_color || has_st)) read_off_vertex_extras(extra, v, records.where());
  }
  if (want_attributes) {
    MeshAttributes& a = *record->attributes;
    if (has_color && colors_ok && nv > 0) {
      a.colors = std::move(colors);
      a.colors_have_alpha = alpha;
    } else if (has_color && nv > 0) {
      record->dropped->push_back("vertex colours: " + color_problem);
    }
    if (has_st && texcoords_ok && nv > 0)
      a.texcoords = std::move(texcoords);
    else if (has_st && nv > 0)
      record->dropped->push_back("texture coordinates: " + st_problem);
  }

  FaceBuilder faces(name, nv, 0, record);
  std::vector<long long> corners;
  for (long long f = 0; f < nf; ++f) {
    if (!records.start(nv + f))
      fail_io(name,
              "truncated: header declares " + std::to_string(nf) + " faces, file holds " + std::to_string(f));
    records.need(tok);  // a record starts with a value
    const long long k = need_int(tok, name, records.where());
    const std::string start = records.start_where();
    auto where = [&] { return start + " (face " + std::to_string(f) + ")"; };
    if (k < 0) fail_io(name, where() + ": negative corner count");
    corners.clear();
    for (long long c = 0; c < k; ++c) {
      if (!records.need(tok))
        fail_io(name, where() + ": face declares " + std::to_string(k) + " corners but lists " +
                          std::to_string(c) + " (file truncated?)");
      corners.push_back(need_int(tok, name, records.where()));
    }
    records.finish(extra);  // numbers after the corners (a face colour) are ignored
    faces.add_checked(corners, where);
  }
  if (records.more())
    fail_io(name, records.where() + ": unexpected data after the " + std::to_string(nf) +
                      " faces the header declares (wrong counts?)");
  mesh.faces = faces.finish(mesh.vertices);
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY: ascii, binary_little_endian, binary_big_endian; any elements and properties (unused ones
// are skipped); positions from vertex x/y/z, faces from the face list vertex_indices (or
// vertex_index).

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ply_type_from_name(std::string_view s, PlyType& t) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, type] : names)
    if (s == n) {
      t = type;
      return true;
    }
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 8;
}

//! The largest value of an integer type: a colour channel of that type is scaled by it to [0, 1].
double ply_max(PlyType t) {
  switch (t) {
    case PlyType::Int8:
      return 127.0;
    case PlyType::UInt8:
      return 255.0;
    case PlyType::Int16:
      return 32767.0;
    case PlyType::UInt16:
      return 65535.0;
    case PlyType::Int32:
      return 2147483647.0;
    case PlyType::UInt32:
      return 4294967295.0;
    default:
      return 1.0;
  }
}

bool ply_is_integer(PlyType t) {
  return t != PlyType::Float32 && t != PlyType::Float64;
}

bool fits_ply_type(long long v, PlyType t) {
  switch (t) {
    case PlyType::Int8:
      return v >= -128 && v <= 127;
    case PlyType::UInt8:
      return v >= 0 && v <= 255;
    case PlyType::Int16:
      return v >= -32768 && v <= 32767;
    case PlyType::UInt16:
      return v >= 0 && v <= 65535;
    case PlyType::Int32:
      return v >= std::numeric_limits<int32_t>::min() && v <= std::numeric_limits<int32_t>::max();
    case PlyType::UInt32:
      return v >= 0 && v <= std::numeric_limits<uint32_t>::max();
    default:
      return true;
  }
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> props;
};

enum class PlyEncoding { Ascii, BinaryLE, BinaryBE };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::vector<PlyElement> elements;
  std::vector<std::string> texture_files;     // "comment TextureFile NAME" (MeshLab), in order
  std::vector<std::string> texture_problems;  // TextureFile lines that name nothing usable
  size_t body_offset = 0;
  long long body_first_line = 1;
};

PlyHeader parse_ply_header(const std::string& name, std::string_view data) {
  PlyHeader h;
  LineReader lines(data);
  std::string_view line;
  if (!lines.next(line) || !(line == "ply" || line == "ply\r"))
    fail_io(name, "not a PLY file: it does not start with the line 'ply'");
  bool have_format = false, ended = false;
  std::unordered_set<std::string> element_names;
  while (lines.next(line)) {
    const std::string where = "header " + lines.where();
    if (line.find('\0') != std::string_view::npos)
      fail_io(name, where + ": contains a NUL byte (corrupt header)");
    LineTokens t(line);
    std::string_view key, a, b, c, d;
    if (!t.next(key)) continue;
    if (key == "comment" && t.next(a) && a == "TextureFile") {
      // The rest of the line as it is (a name may hold spaces or '#'), trimmed at the ends.
      std::string_view file = line.substr(line.find("TextureFile") + 11);
      while (!file.empty() && is_blank(file.front())) file.remove_prefix(1);
      while (!file.empty() && is_blank(file.back())) file.remove_suffix(1);
      const bool printable = std::all_of(file.begin(), file.end(), [](char c) {
        return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
      });
      if (!file.empty() && printable)
        h.texture_files.emplace_back(file);
      else
        h.texture_problems.push_back("texture image: " + where + ": a TextureFile comment " +
                                     (file.empty() ? "without a name" : "with a control character"));
      continue;
    }
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      ended = true;
      break;
    }
    if (key == "format") {
      if (!t.next(a) || !t.next(b)) fail_io(name, where + ": incomplete format line");
      if (a == "ascii")
        h.encoding = PlyEncoding::Ascii;
      else if (a == "binary_little_endian")
        h.encoding = PlyEncoding::BinaryLE;
      else if (a == "binary_big_endian")
        h.encoding = PlyEncoding::BinaryBE;
      else
        fail_io(name, where + ": unknown PLY format " + quote_token(a));
      if (b != "1.0") fail_io(name, where + ": unsupported PLY version " + quote_token(b));
      have_format = true;
    } else if (key == "element") {
      if (!t.next(a) || !t.next(b)) fail_io(name, where + ": incomplete element line");
      PlyElement e;
      e.name = std::string(a);
      e.count = need_int(b, name, where);
      if (e.count < 0) fail_io(name, where + ": negative element count");
      // A set, not a search of the earlier elements: 300k declarations of empty elements took 53 s.
      if (!element_names.insert(e.name).second)
        fail_io(name, where + ": element " + quote_token(a) + " declared twice");
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) fail_io(name, where + ": property before any element");
      PlyProperty p;
      if (!t.next(a)) fail_io(name, where + ": incomplete property line");
      if (a == "list") {
        if (!t.next(b) || !t.next(c) || !t.next(d)) fail_io(name, where + ": incomplete list property line");
        p.is_list = true;
        if (!ply_type_from_name(b, p.count_type)) fail_io(name, where + ": unknown type " + quote_token(b));
        if (!ply_is_integer(p.count_type)) fail_io(name, where + ": list count type must be an integer type");
        if (!ply_type_from_name(c, p.type)) fail_io(name, where + ": unknown type " + quote_token(c));
        p.name = std::string(d);
      } else {
        if (!t.next(b)) fail_io(name, where + ": incomplete property line");
        if (!ply_type_from_name(a, p.type)) fail_io(name, where + ": unknown type " + quote_token(a));
        p.name = std::string(b);
      }
      h.elements.back().props.push_back(std::move(p));
    } else {
      fail_io(name, where + ": unexpected header line starting with " + quote_token(key));
    }
  }
  if (!ended) fail_io(name, "truncated: PLY header has no 'end_header' line");
  if (!have_format) fail_io(name, "PLY header has no 'format' line");
  h.body_offset = lines.pos();
  h.body_first_line = lines.line_no() + 1;
  return h;
}

struct PlyValue {
  long long i = 0;  // valid for integer types
  double d = 0.0;
};

//! Values of an ascii PLY body, one token each.
class PlyAsciiSource {
 public:
  PlyAsciiSource(const std::string& name, std::string_view body, long long first_line)
      : name_(name), cursor_(body, first_line) {}
  bool read(PlyType t, PlyValue& v) {
    std::string_view tok;
    if (!cursor_.next(tok)) return false;
    if (ply_is_integer(t)) {
      v.i = need_int(tok, name_, cursor_.where());
      if (!fits_ply_type(v.i, t))
        fail_io(name_, cursor_.where() + ": value " + quote_token(tok) + " does not fit its declared type");
      v.d = static_cast<double>(v.i);
    } else {
      v.d = need_double(tok, name_, cursor_.where());
    }
    return true;
  }
  //! Describes leftover data after the last element, or returns "".
  std::string leftover() {
    return cursor_.at_end() ? "" : cursor_.where() + ": data after the last declared element";
  }

 private:
  const std::string& name_;
  TextCursor cursor_;
};

//! Values of a binary PLY body; converts from the file's byte order.
class PlyBinarySource {
 public:
  PlyBinarySource(std::string_view body, bool big_endian)
      : p_(body.data()), end_(body.data() + body.size()), swap_(big_endian == host_is_little_endian()) {}
  bool read(PlyType t, PlyValue& v) {
    const size_t n = ply_size(t);
    if (static_cast<size_t>(end_ - p_) < n) return false;
    unsigned char b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (t) {
      case PlyType::Int8:
        v.i = static_cast<int8_t>(b[0]);
        break;
      case PlyType::UInt8:
        v.i = b[0];
        break;
      case PlyType::Int16:
        v.i = load<int16_t>(b);
        break;
      case PlyType::UInt16:
        v.i = load<uint16_t>(b);
        break;
      case PlyType::Int32:
        v.i = load<int32_t>(b);
        break;
      case PlyType::UInt32:
        v.i = load<uint32_t>(b);
        break;
      case PlyType::Float32:
        v.d = load<float>(b);
        return true;
      case PlyType::Float64:
        v.d = load<double>(b);
        return true;
    }
    v.d = static_cast<double>(v.i);
    return true;
  }
  std::string leftover() const {
    return p_ == end_ ? "" : std::to_string(end_ - p_) + " bytes of data after the last declared element";
  }

 private:
  template <class T>
  static T load(const unsigned char* b) {
    T x;
    std::memcpy(&x, b, sizeof x);
    return x;
  }
  const char* p_;
  const char* end_;
  bool swap_ = false;
};

std::string plural_element(const PlyElement& e) {
  if (e.name == "vertex") return "vertices";
  if (e.name == "face") return "faces";
  return quote_token(e.name) + " elements";
}

template <class Source>
TriMesh read_ply_body(const std::string& name, const PlyHeader& h, Source& src, FaceRecord* record) {
  long long num_vertices = 0;
  for (const PlyElement& e : h.elements)
    if (e.name == "vertex") num_vertices = e.count;
  check_vertex_count(num_vertices, name);

  TriMesh mesh;
  FaceBuilder faces(name, num_vertices, 0, record);
  std::vector<long long> corners;
  PlyValue value;
  const bool want_attributes = record && record->attributes;
  MeshAttributes attrs;
  // Per face (polygon) in file order: its corners, their (u, v) (texcoord lists) and its image.
  std::vector<int> poly_sizes, poly_vertices;
  std::vector<long long> poly_textures;
  std::vector<std::array<double, 2>> poly_uv;
  std::vector<double> face_uv;
  std::string uv_problem;
  for (const PlyElement& e : h.elements) {
    // An element without properties holds no data, whatever its count; but vertices must have
    // coordinates (faces are checked against the vertex count).
    if (e.props.empty() && !(e.name == "vertex" && e.count > 0)) continue;
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    std::array<int, 3> xyz{-1, -1, -1};
    int index_prop = -1;
    for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
      const PlyProperty& p = e.props[k];
      for (int c = 0; c < 3; ++c)
        if (is_vertex && p.name == std::string(1, static_cast<char>('x' + c))) {
          if (p.is_list) fail_io(name, "vertex property " + p.name + " must not be a list");
          // Which one holds the coordinate? (The last was read, silently.)
          if (xyz[c] >= 0) fail_io(name, "vertex property " + p.name + " declared twice");
          xyz[c] = k;
        }
      if (is_face && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (!ply_is_integer(p.type)) fail_io(name, "face property " + p.name + " must have an integer type");
        if (index_prop >= 0)
          fail_io(name, "face properties " + e.props[index_prop].name + " and " + p.name +
                            ": two lists of vertex indices");
        index_prop = k;
      }
    }
    if (is_vertex)
      for (int c = 0; c < 3; ++c)
        if (xyz[c] < 0)
          fail_io(name, std::string("vertex element has no property ") + static_cast<char>('x' + c));
    // Colour channels (red green blue [alpha], or diffuse_*) and texture coordinates (u v, s t,
    // texture_u texture_v or texture_s texture_t) of the vertices, if all their parts are there.
    std::array<int, 4> rgba{-1, -1, -1, -1};
    std::array<int, 2> uv{-1, -1};
    if (is_vertex && want_attributes) {
      auto find = [&](std::initializer_list<const char*> names) {
        for (const char* n : names)
          for (int k = 0; k < static_cast<int>(e.props.size()); ++k)
            if (!e.props[k].is_list && e.props[k].name == n) return k;
        return -1;
      };
      rgba = {find({"red", "diffuse_red"}), find({"green", "diffuse_green"}), find({"blue", "diffuse_blue"}),
              find({"alpha", "diffuse_alpha"})};
      const int channels = (rgba[0] >= 0) + (rgba[1] >= 0) + (rgba[2] >= 0);
      if (channels > 0 && channels < 3) {
        record->dropped->push_back("vertex colours: the vertex element has only " + std::to_string(channels) +
                                   " of the red, green and blue properties");
        rgba = {-1, -1, -1, -1};
      }
      if (rgba[0] < 0) rgba[3] = -1;
      const std::array<std::array<const char*, 2>, 4> pairs{
          {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
      std::string half;  // a property of a pair whose partner is missing (or a list)
      for (const auto& pair : pairs) {
        uv = {find({pair[0]}), find({pair[1]})};
        if (uv[0] >= 0 && uv[1] >= 0) break;
        uv = {-1, -1};
        for (const PlyProperty& p : e.props)
          if (half.empty() && (p.name == pair[0] || p.name == pair[1])) half = p.name;
      }
      if (uv[0] < 0 && !half.empty())
        record->dropped->push_back("texture coordinates: the vertex element has " + half +
                                   " without its partner (or as a list)");
      if (rgba[0] >= 0) {
        attrs.colors.reserve(static_cast<size_t>(std::min<long long>(e.count, 1 << 20)));
        attrs.colors_have_alpha = rgba[3] >= 0;
      }
      if (uv[0] >= 0) attrs.texcoords.reserve(static_cast<size_t>(std::min<long long>(e.count, 1 << 20)));
    }
    // MeshLab's texture coordinates per face corner (a list of 2n numbers) and image per face.
    int texcoord_prop = -1, texnumber_prop = -1;
    if (is_face && want_attributes)
      for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
        const PlyProperty& p = e.props[k];
        if (p.is_list && (p.name == "texcoord" || p.name == "texcoords") && texcoord_prop < 0)
          texcoord_prop = k;
        if (p.name == "texnumber") {
          if (!p.is_list && ply_is_integer(p.type))
            texnumber_prop = k;
          else
            record->dropped->push_back(
                "texture images per face: the face property texnumber is not an integer");
        }
      }
    if (is_face && index_prop < 0) fail_io(name, "face element has no list property vertex_indices");
    if (is_vertex) mesh.vertices.reserve(static_cast<size_t>(std::min<long long>(e.count, 1 << 20)));

    auto truncated = [&](long long done) {
      fail_io(name, "truncated: header declares " + std::to_string(e.count) + " " + plural_element(e) +
                        ", file holds " + std::to_string(done));
    };
    for (long long i = 0; i < e.count; ++i) {
      Vec3 p = Vec3::Zero();
      long long texnumber = -1;
      std::array<double, 4> color{0.0, 0.0, 0.0, 1.0};
      std::array<double, 2> tex{0.0, 0.0};
      for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
        const PlyProperty& prop = e.props[k];
        if (!prop.is_list) {
          if (!src.read(prop.type, value)) truncated(i);
          if (k == texnumber_prop) texnumber = value.i;
          for (int c = 0; c < 3; ++c)
            if (k == xyz[c]) p[c] = value.d;
          for (int c = 0; c < 4; ++c)
            if (k == rgba[c]) color[c] = ply_is_integer(prop.type) ? value.d / ply_max(prop.type) : value.d;
          for (int c = 0; c < 2; ++c)
            if (k == uv[c]) tex[c] = value.d;
          continue;
        }
        if (!src.read(prop.count_type, value)) truncated(i);
        const long long n = value.i;
        if (n < 0) fail_io(name, plural_element(e) + " " + std::to_string(i) + ": negative list length");
        const bool keep = k == index_prop, keep_uv = k == texcoord_prop;
        if (keep) corners.clear();
        if (keep_uv) face_uv.clear();
        for (long long j = 0; j < n; ++j) {  // each item consumes input, so this is bounded by the file size
          if (!src.read(prop.type, value)) truncated(i);
          if (keep) corners.push_back(value.i);
          if (keep_uv) face_uv.push_back(value.d);
        }
        if (keep) faces.add_checked(corners, [&] { return "face " + std::to_string(i); });
      }
      if (is_face && want_attributes) {
        poly_sizes.push_back(static_cast<int>(corners.size()));
        for (long long c : corners) poly_vertices.push_back(static_cast<int>(c));
        if (texcoord_prop >= 0) {
          if (face_uv.size() == 2 * corners.size()) {
            for (std::size_t c = 0; c < corners.size(); ++c)
              poly_uv.push_back({face_uv[2 * c], face_uv[2 * c + 1]});
          } else if (uv_problem.empty()) {
            uv_problem = "texture coordinates: face " + std::to_string(i) + "'s texcoord list has " +
                         std::to_string(face_uv.size()) + " values for " + std::to_string(corners.size()) +
                         " corners";
          }
        }
        if (texnumber_prop >= 0) poly_textures.push_back(texnumber);
      }
      if (is_vertex) {
        mesh.vertices.push_back(p);
        if (rgba[0] >= 0) attrs.colors.push_back(color);
        if (uv[0] >= 0) attrs.texcoords.push_back(tex);
      }
    }
  }
  const std::string rest = src.leftover();
  if (!rest.empty()) fail_io(name, rest + " (wrong counts in the header?)");
  // The faces' indices were checked against the declared count, which is what was read: the
  // header names one vertex element, and one with a count has coordinates.
  assert(static_cast<long long>(mesh.vertices.size()) == num_vertices);
  mesh.faces = faces.finish(mesh.vertices);
  if (want_attributes) {
    if (!uv_problem.empty()) {
      record->dropped->push_back(uv_problem);
    } else if (!poly_uv.empty()) {
      // One (u, v) per polygon corner: per vertex where each vertex's corners agree, else per
      // triangle corner (seams), mapped through the triangulation by the corners' vertices.
      std::vector<int> first(mesh.vertices.size(), -1);
      bool seams = false;
      for (std::size_t c = 0; c < poly_vertices.size(); ++c) {
        int& f = first[static_cast<std::size_t>(poly_vertices[c])];
        if (f < 0)
          f = static_cast<int>(c);
        else
          seams = seams || poly_uv[static_cast<std::size_t>(f)] != poly_uv[c];
      }
      // Vertices with u v too: the lists win where they say more (seams) or otherwise, noted.
      bool differ = false;
      for (std::size_t v = 0; v < first.size() && !attrs.texcoords.empty(); ++v)
        differ =
            differ || (first[v] >= 0 && attrs.texcoords[v] != poly_uv[static_cast<std::size_t>(first[v])]);
      if (differ || (seams && !attrs.texcoords.empty()))
        record->dropped->push_back(
            "texture coordinates per vertex (u v): the faces' texcoord lists differ from them and are kept "
            "instead");
      if (!seams && (attrs.texcoords.empty() || differ)) {
        attrs.texcoords.assign(mesh.vertices.size(), {0.0, 0.0});
        for (std::size_t v = 0; v < first.size(); ++v)
          if (first[v] >= 0) attrs.texcoords[v] = poly_uv[static_cast<std::size_t>(first[v])];
      } else if (seams) {
        attrs.texcoords.clear();
        attrs.corner_uv = poly_uv;
        attrs.corner_uv_index =
            triangle_corner_offsets(mesh.faces, mesh.vertices.size(), poly_sizes, poly_vertices);
      }
    }
    // Per triangle, its polygon's image; a number naming no image (beyond the TextureFile lines,
    // or below -1) cannot be kept.
    attrs.texture_files = h.texture_files;
    for (const std::string& d : h.texture_problems) record->dropped->push_back(d);
    const long long images = static_cast<long long>(attrs.texture_files.size());
    const auto bad = std::find_if(poly_textures.begin(), poly_textures.end(),
                                  [&](long long t) { return t < -1 || t >= images; });
    if (bad != poly_textures.end()) {
      record->dropped->push_back("texture images per face: a face's texnumber " + std::to_string(*bad) +
                                 " names no TextureFile comment (" + std::to_string(images) +
                                 " in the header)");
    } else if (!poly_textures.empty() && poly_textures.size() == poly_sizes.size()) {
      for (int p : triangle_polygons(mesh.faces.size(), poly_sizes))
        attrs.face_textures.push_back(static_cast<int>(poly_textures[p]));
    }
    *record->attributes = std::move(attrs);
  }
  return mesh;
}

TriMesh read_ply(const std::string& name, std::string_view data, FaceRecord* record) {
  const PlyHeader h = parse_ply_header(name, data);
  const std::string_view body = data.substr(h.body_offset);
  if (h.encoding == PlyEncoding::Ascii) {
    reject_nul_bytes(body, name, "ascii PLY body");
    PlyAsciiSource src(name, body, h.body_first_line);
    return read_ply_body(name, h, src, record);
  }
  PlyBinarySource src(body, h.encoding == PlyEncoding::BinaryBE);
  return read_ply_body(name, h, src, record);
}

// ---------------------------------------------------------------------------------------------
// STL. Corners are welded: bitwise-equal positions (with -0 == +0) become one vertex, numbered in
// order of first use.

// The STL readers' welder: internal::Welder with the readers' vertex-count limit.
class Welder {
 public:
  explicit Welder(const std::string& name) : name_(name) {}
  long long index_of(const Vec3& p) {
    const long long i = welder_.index_of(p);
    if (i + 1 == static_cast<long long>(welder_.vertices.size())) check_vertex_count(i + 1, name_);
    return i;
  }
  std::vector<Vec3>& vertices() { return welder_.vertices; }

 private:
  const std::string& name_;
  internal::Welder welder_;
};

TriMesh read_stl_binary(const std::string& name, std::string_view data, uint32_t count) {
  Welder welder(name);
  // The face count is at most 3 * count <= 2^32 * 3; faces must index with int.
  if (3ll * count > kMaxIndexCount) fail_io(name, "too many triangles (" + std::to_string(count) + ")");
  FaceBuilder faces(name, kMaxIndexCount, 0);
  std::vector<long long> corners(3);
  const char* rec = data.data() + 84;
  for (uint32_t t = 0; t < count; ++t, rec += 50) {
    for (int c = 0; c < 3; ++c) {
      const char* p = rec + 12 + 12 * c;  // after the 12-byte normal
      corners[c] = welder.index_of(Vec3(load_le<float>(p), load_le<float>(p + 4), load_le<float>(p + 8)));
    }
    faces.add_checked(corners,
                      [&] { return "facet " + std::to_string(t) + " (corners weld to equal positions)"; });
  }
  TriMesh mesh;
  mesh.vertices = std::move(welder.vertices());
  mesh.faces = faces.finish(mesh.vertices);
  return mesh;
}

TriMesh read_stl_ascii(const std::string& name, std::string_view text) {
  TextCursor cur(text, 1);
  std::string_view tok;
  auto expect = [&](const char* word) {
    if (!cur.next(tok)) fail_io(name, std::string("truncated: file ends where '") + word + "' was expected");
    if (!iequals(tok, word))
      fail_io(name, cur.where() + ": expected '" + word + "', found " + quote_token(tok));
  };
  auto number = [&]() {
    if (!cur.next(tok)) fail_io(name, "truncated: file ends inside a facet");
    return need_double(tok, name, cur.where());
  };
  expect("solid");
  cur.skip_rest_of_line();  // the solid's name

  Welder welder(name);
  FaceBuilder faces(name, kMaxIndexCount, 0);
  std::vector<long long> corners;
  long long facet = 0;
  for (;;) {
    if (!cur.next(tok)) fail_io(name, "truncated: no 'endsolid' line");
    if (iequals(tok, "endsolid")) {
      cur.skip_rest_of_line();
      if (cur.at_end()) break;
      expect("solid");  // several solids in one file are concatenated
      cur.skip_rest_of_line();
      continue;
    }
    if (!iequals(tok, "facet"))
      fail_io(name, cur.where() + ": expected 'facet' or 'endsolid', found " + quote_token(tok));
    const std::string where = cur.where() + " (facet " + std::to_string(facet) + ")";
    expect("normal");
    for (int k = 0; k < 3; ++k) number();  // the normal is redundant: orientation comes from the corner order
    expect("outer");
    expect("loop");
    corners.clear();
    for (;;) {
      if (!cur.next(tok)) fail_io(name, "truncated: file ends inside a facet");
      if (iequals(tok, "endloop")) break;
      if (!iequals(tok, "vertex"))
        fail_io(name, cur.where() + ": expected 'vertex' or 'endloop', found " + quote_token(tok));
      Vec3 p;
      for (int k = 0; k < 3; ++k) p[k] = number();
      corners.push_back(welder.index_of(p));
    }
    expect("endfacet");
    faces.add_checked(corners, [&] { return where; });
    ++facet;
  }
  TriMesh mesh;
  mesh.vertices = std::move(welder.vertices());
  mesh.faces = faces.finish(mesh.vertices);
  return mesh;
}

TriMesh read_stl(const std::string& name, std::string_view data) {
  // Binary STL: 80-byte header, uint32 count, 50 bytes per triangle. A matching size decides for
  // binary even if the header starts with "solid" (some exporters write that).
  uint32_t count = 0;
  if (data.size() >= 84) count = load_le<uint32_t>(data.data() + 80);
  const unsigned long long expected = 84ull + 50ull * count;
  if (data.size() >= 84 && data.size() == expected) return read_stl_binary(name, data, count);

  const size_t bom = data.substr(0, 3) == kUtf8Bom ? 3 : 0;
  size_t start = bom;
  while (start < data.size() && (is_blank(data[start]) || data[start] == '\n')) ++start;
  const bool looks_ascii = data.size() - start >= 5 && iequals(data.substr(start, 5), "solid") &&
                           data.find('\0') == std::string_view::npos;
  if (looks_ascii) return read_stl_ascii(name, data.substr(bom));
  if (data.size() < 84)
    fail_io(name, "not an STL file: " + std::to_string(data.size()) +
                      " bytes is too short for a binary STL and it does not start with 'solid'");
  if (data.size() < expected)
    fail_io(name, "truncated: header declares " + std::to_string(count) + " triangles, file holds " +
                      std::to_string((data.size() - 84) / 50));
  fail_io(name, "binary STL header declares " + std::to_string(count) + " triangles (" +
                    std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()) +
                    " bytes");
}

// ---------------------------------------------------------------------------------------------
// Validation.

// Where a face of ordinary edges is zero area only for the mesh's size (its longest edge \p edge
// under 1e-4 of the diagonal \p diag, both scaled alike), the size likely comes from a stray
// vertex: "; vertex V at (x, y, z) is the farthest from the others' median: an outlier?". Else "".
std::string outlier_hint(const TriMesh& mesh, const std::vector<char>& used, double edge, double diag) {
  if (!(edge < 1e-4 * diag)) return "";
  std::vector<Vec3> points;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) points.push_back(mesh.vertices[v]);
  const Vec3 median = coordinate_median(points);
  size_t far = 0;
  double far_d = -1.0;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) {
      const double d = (mesh.vertices[v] - median).cwiseAbs().maxCoeff();  // no overflow
      if (d > far_d) far_d = d, far = v;
    }
  const Vec3& p = mesh.vertices[far];
  char text[160];
  std::snprintf(text, sizeof text,
                "; vertex %zu at (%.6g, %.6g, %.6g) is the farthest from the others' median: an outlier?",
                far, p.x(), p.y(), p.z());
  return text;
}

//! Returns the first problem of \p mesh (without the name prefix), or "" if it is valid; in
//! \p face (if given) the face it names first, or -1.
std::string find_mesh_problem(const TriMesh& mesh, long long* face = nullptr) {
  long long ignored = -1;
  long long& at = face ? *face : ignored;
  at = -1;
  if (mesh.faces.empty()) return "no faces";
  const long long nv = static_cast<long long>(mesh.vertices.size());
  if (nv > kMaxIndexCount) return "too many vertices";
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (!mesh.vertices[v].allFinite()) return "vertex " + std::to_string(v) + " has a non-finite coordinate";
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    at = static_cast<long long>(f);
    for (int i : t)
      if (i < 0 || i >= nv)
        return "face " + std::to_string(f) + " has vertex index " + std::to_string(i) +
               " out of range (mesh has " + std::to_string(nv) + " vertices)";
    if (t[0] == t[1] || t[0] == t[2] || t[1] == t[2])
      return "face " + std::to_string(f) + " has repeated vertex index " +
             std::to_string(t[0] == t[1] || t[0] == t[2] ? t[0] : t[1]);
  }
  at = -1;
  // Zero area relative to the model's size, so the test does not depend on units. Coordinates
  // are scaled by a power of two (exact) so squares neither overflow nor underflow at 1e+-200.
  // The size is the faces' (a vertex in no face, however far, does not make them small).
  std::vector<char> used(static_cast<size_t>(nv), 0);
  for (const Face& t : mesh.faces)
    for (int i : t) used[static_cast<size_t>(i)] = 1;
  double max_abs = 0.0;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) max_abs = std::max(max_abs, mesh.vertices[v].cwiseAbs().maxCoeff());
  int exponent = 0;
  std::frexp(max_abs, &exponent);
  const int scale_exponent = max_abs > 0.0 ? std::min(-exponent, 1000) : 0;  // 2^1000 < DBL_MAX
  const double scale = std::ldexp(1.0, scale_exponent);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) {
      lo = lo.cwiseMin(mesh.vertices[v] * scale);
      hi = hi.cwiseMax(mesh.vertices[v] * scale);
    }
  const double diag = (hi - lo).norm();  // bbox_diagonal(vertices) * scale
  const double min_double_area = internal::kZeroAreaRelative * diag * diag;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    const Vec3 a = mesh.vertices[t[0]] * scale, b = mesh.vertices[t[1]] * scale,
               c = mesh.vertices[t[2]] * scale;
    const double double_area = triangle_area_normal(a, b, c).norm();
    if (double_area == 0.0 || double_area <= min_double_area) {
      at = static_cast<long long>(f);
      const std::string what = "face " + std::to_string(f) + " has zero area";
      // Small only for the mesh's size, say, next to a vertex at 1e300 (whose scale can flush the
      // face's area to 0): give both, unscaled.
      const double area =
          double_area > 0.0
              ? std::ldexp(0.5 * double_area, -2 * scale_exponent)
              : 0.5 * triangle_area_normal(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]])
                          .norm();
      const double diagonal = std::ldexp(diag, -scale_exponent);
      if (area == 0.0) return what;
      // Near DBL_MAX the unscaled area or diagonal can overflow: then only the reason is given.
      if (!std::isfinite(area) || !std::isfinite(diagonal)) return what + " for the mesh's size";
      char sizes[96];
      std::snprintf(sizes, sizeof sizes, " for the mesh's size (area %.3g, bounding-box diagonal %.3g", area,
                    diagonal);
      return what + sizes +
             outlier_hint(mesh, used, std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()}), diag) + ")";
    }
  }

  // Edge uses bucketed by their smaller vertex (a counting sort): linear time, 8 bytes per use.
  struct Use {
    int other;      // larger vertex of the edge
    uint32_t code;  // face * 2 + (1 if the face traverses it from smaller to larger)
  };
  const size_t nf = mesh.faces.size();
  std::vector<size_t> start(static_cast<size_t>(nv) + 1, 0);
  for (const Face& t : mesh.faces)
    for (int c = 0; c < 3; ++c) ++start[static_cast<size_t>(std::min(t[c], t[(c + 1) % 3])) + 1];
  for (size_t v = 0; v < static_cast<size_t>(nv); ++v) start[v + 1] += start[v];
  std::vector<Use> uses(3 * nf);
  std::vector<size_t> fill(start.begin(), start.end() - 1);
  for (size_t f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = mesh.faces[f][c], b = mesh.faces[f][(c + 1) % 3];
      uses[fill[static_cast<size_t>(std::min(a, b))]++] = {std::max(a, b),
                                                           static_cast<uint32_t>(f * 2 + (a < b ? 1 : 0))};
    }
  // Report the offending edge whose first face comes first, so messages are deterministic.
  size_t best_face = nf;
  std::string problem;
  for (size_t v = 0; v < static_cast<size_t>(nv); ++v) {
    Use* b = uses.data() + start[v];
    Use* e = uses.data() + start[v + 1];
    std::sort(b, e, [](const Use& x, const Use& y) {
      return x.other != y.other ? x.other < y.other : x.code < y.code;
    });
    for (Use* g = b; g != e;) {
      Use* h = g;
      while (h != e && h->other == g->other) ++h;
      const size_t n = static_cast<size_t>(h - g);
      const size_t first_face = g->code / 2;
      // Named only for a problem: building the name for every edge took a tenth of reading a
      // million quads.
      auto edge = [&] { return "edge (" + std::to_string(v) + "," + std::to_string(g->other) + ")"; };
      if (n > 2 && first_face < best_face) {
        best_face = first_face;
        problem = edge() + " is non-manifold: shared by " + std::to_string(n) + " faces (";
        for (size_t i = 0; i < std::min<size_t>(n, 6); ++i)
          problem += (i ? ", " : "") + std::to_string(g[i].code / 2);
        problem += n > 6 ? ", ...)" : ")";
      } else if (n == 2 && (g[0].code & 1) == (g[1].code & 1) && first_face < best_face) {
        best_face = first_face;
        const bool fwd = g[0].code & 1;
        problem = edge() + " has inconsistently oriented faces: faces " + std::to_string(g[0].code / 2) +
                  " and " + std::to_string(g[1].code / 2) + " both traverse it from " +
                  std::to_string(fwd ? v : static_cast<size_t>(g->other)) + " to " +
                  std::to_string(fwd ? static_cast<size_t>(g->other) : v);
      }
      g = h;
    }
  }
  if (!problem.empty()) at = static_cast<long long>(best_face);
  return problem;
}

//! " (...)": which of the file's faces \p face of the triangulated mesh comes from, where the file
//! has polygons of more than 3 corners (\p cuts, FaceRecord), so that face numbers differ from the
//! file's; "" otherwise.
std::string file_face_note(long long face, const std::vector<FaceRecord::Cut>& cuts) {
  if (face < 0 || cuts.empty()) return "";
  const size_t f = static_cast<size_t>(face);
  const std::string head = " (face numbers count triangles: face " + std::to_string(face) + " is ";
  size_t extra = 0;  // triangles beyond one per file face, of the cut polygons before f
  for (const FaceRecord::Cut& c : cuts) {
    if (f < c.first_face) break;
    if (f < c.first_face + c.n - 2)
      return head + "one of the " + std::to_string(c.n - 2) + " triangles cut from the file's " +
             ordinal(c.first_face - extra + 1) + " face, a polygon of " + std::to_string(c.n) + " corners)";
    extra += c.n - 3;
  }
  return head + "the file's " + ordinal(f - extra + 1) + " face)";
}

// ---------------------------------------------------------------------------------------------
// Writers. Text is produced with std::to_chars: the shortest decimal that reads back to the
// identical double, independent of the locale.

//! Builds file contents in memory and writes them out in 1 MiB chunks.
class ChunkedWriter {
 public:
  ChunkedWriter(const std::string& name, const std::string& tmp_path)
      : name_(name), out_(tmp_path, std::ios::binary | std::ios::trunc) {
    if (!out_) fail_io(name_, "cannot open temporary file " + tmp_path + " for writing");
    buf_.reserve(kChunk + 256);
  }
  void text(std::string_view s) { buf_.append(s.data(), s.size()); }
  void number(double x) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, x);
    buf_.append(tmp, r.ptr);
  }
  void integer(long long x) {
    char tmp[24];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, x);
    buf_.append(tmp, r.ptr);
  }
  template <class T>
  void binary_le(T x) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &x, sizeof x);
    if (!host_is_little_endian()) std::reverse(b, b + sizeof b);
    buf_.append(reinterpret_cast<const char*>(b), sizeof b);
  }
  void maybe_flush() {
    if (buf_.size() >= kChunk) flush();
  }
  void close() {
    flush();
    out_.close();
    if (!out_) fail_io(name_, "writing failed (disk full?)");
  }

 private:
  void flush() {
    out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    if (!out_) fail_io(name_, "writing failed (disk full?)");
    buf_.clear();
  }
  static constexpr size_t kChunk = 1 << 20;
  const std::string& name_;
  std::ofstream out_;
  std::string buf_;
};

void write_vec(ChunkedWriter& w, const Vec3& p) {
  w.number(p[0]);
  w.text(" ");
  w.number(p[1]);
  w.text(" ");
  w.number(p[2]);
}

// A number that reads back as a float, not an integer: OFF tells a colour of integers (0-255)
// from one of floats (0-1) by this.
void float_token(ChunkedWriter& w, double x) {
  char tmp[40];
  const auto r = std::to_chars(tmp, tmp + 32, x);
  std::string_view t(tmp, static_cast<std::size_t>(r.ptr - tmp));
  w.text(t);
  if (t.find_first_of(".eEn") == std::string_view::npos) w.text(".0");  // "n": nan, inf
}

// The colour channels written: RGB, or RGBA if the colours came with alpha.
int color_channels(const MeshAttributes& a) {
  return a.colors_have_alpha ? 4 : 3;
}

// Faces are triangles (Face) or polygons (std::vector<int>): anything with size() and [].
// \p a: the vertices' colours and texture coordinates, or null.
template <class F>
void write_obj(const std::vector<Vec3>& vertices, const std::vector<F>& faces, ChunkedWriter& w,
               const MeshAttributes* a = nullptr) {
  const bool colors = a && !a->colors.empty(), uv = a && !a->texcoords.empty();
  // Per face corner (texture seams) only for triangles, whose corners the indices follow.
  const bool corner_uv = a && !a->corner_uv_index.empty() && a->corner_uv_index.size() == faces.size();
  const bool materials = a && a->face_materials.size() == faces.size();
  // The count comment lets read_mesh detect truncation (OBJ has no counts of its own).
  w.text("# " + std::to_string(vertices.size()) + " vertices, " + std::to_string(faces.size()) + " faces\n");
  if (a && !a->material_library.empty()) w.text("mtllib " + a->material_library + "\n");
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    w.text("v ");
    write_vec(w, vertices[v]);
    if (colors)
      for (int c = 0; c < color_channels(*a); ++c) {
        w.text(" ");
        w.number(a->colors[v][c]);
      }
    w.text("\n");
    w.maybe_flush();
  }
  if (uv || corner_uv)
    for (const auto& t : uv ? a->texcoords : a->corner_uv) {
      w.text("vt ");
      w.number(t[0]);
      w.text(" ");
      w.number(t[1]);
      w.text("\n");
      w.maybe_flush();
    }
  int material = -1;
  if (materials) {
    // The reader numbers materials by first mention: where the faces' first uses would number
    // them otherwise (or leave one out), every name is mentioned first, in order.
    std::vector<int> first_use;
    std::vector<char> seen(a->material_names.size(), 0);
    for (int m : a->face_materials)
      if (m >= 0 && !seen[m]) seen[m] = 1, first_use.push_back(m);
    bool in_order = first_use.size() == a->material_names.size();
    for (std::size_t k = 0; in_order && k < first_use.size(); ++k)
      in_order = first_use[k] == static_cast<int>(k);
    if (!in_order) {
      for (const std::string& n : a->material_names) w.text("usemtl " + n + "\n");
      material = static_cast<int>(a->material_names.size()) - 1;
    }
  }
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const F& f = faces[j];
    if (materials && a->face_materials[j] != material) {
      material = a->face_materials[j];
      w.text(material < 0 ? std::string("usemtl\n") : "usemtl " + a->material_names[material] + "\n");
    }
    w.text("f");
    for (std::size_t c = 0; c < f.size(); ++c) {
      w.text(" ");
      w.integer(f[c] + 1ll);
      if (uv) {
        w.text("/");
        w.integer(f[c] + 1ll);
      } else if (corner_uv) {
        w.text("/");
        w.integer(a->corner_uv_index[j][c] + 1ll);
      }
    }
    w.text("\n");
    w.maybe_flush();
  }
}

// "n a b c ..": a face in OFF's and ASCII PLY's face syntax (0-based), without the line break.
template <class F>
void write_face_corners(ChunkedWriter& w, const F& f) {
  w.integer(static_cast<long long>(f.size()));
  for (int i : f) {
    w.text(" ");
    w.integer(i);
  }
}

template <class F>
void write_off(const std::vector<Vec3>& vertices, const std::vector<F>& faces, ChunkedWriter& w,
               const MeshAttributes* a = nullptr) {
  const bool colors = a && !a->colors.empty(), uv = a && !a->texcoords.empty();
  w.text(std::string(uv ? "ST" : "") + (colors ? "C" : "") + "OFF\n" + std::to_string(vertices.size()) + " " +
         std::to_string(faces.size()) + " 0\n");
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    write_vec(w, vertices[v]);
    if (colors)
      for (int c = 0; c < color_channels(*a); ++c) {
        w.text(" ");
        float_token(w, a->colors[v][c]);
      }
    if (uv) {
      w.text(" ");
      w.number(a->texcoords[v][0]);
      w.text(" ");
      w.number(a->texcoords[v][1]);
    }
    w.text("\n");
    w.maybe_flush();
  }
  for (const F& f : faces) {
    write_face_corners(w, f);
    w.text("\n");
    w.maybe_flush();
  }
}

// Whether every colour channel is k / 255 for an integer k in [0, 255], as 8-bit colours read:
// then they are written as uchar, which every PLY reader takes.
bool colors_are_8_bit(const MeshAttributes& a) {
  for (const auto& c : a.colors)
    for (double x : c) {
      if (!(x >= 0.0 && x <= 1.0)) return false;
      if (std::round(x * 255.0) / 255.0 != x) return false;
    }
  return true;
}

template <class F>
void write_ply(const std::vector<Vec3>& vertices, const std::vector<F>& faces, ChunkedWriter& w, bool binary,
               const MeshAttributes* a = nullptr) {
  const bool colors = a && !a->colors.empty(), uv = a && !a->texcoords.empty();
  const bool uchar = colors && colors_are_8_bit(*a);
  const int channels = colors ? color_channels(*a) : 0;
  std::string props = "property double x\nproperty double y\nproperty double z\n";
  static const char* const kChannel[] = {"red", "green", "blue", "alpha"};
  for (int c = 0; c < channels; ++c)
    props += std::string("property ") + (uchar ? "uchar " : "double ") + kChannel[c] + "\n";
  if (uv) props += "property double texture_u\nproperty double texture_v\n";
  // MeshLab's layout for texture seams and images: per face a list of 2n numbers and an image.
  const bool corner_uv = a && !a->corner_uv_index.empty() && a->corner_uv_index.size() == faces.size();
  const bool textures = a && a->face_textures.size() == faces.size();
  std::string comments = "comment written by Strata\n";
  if (a)
    for (const std::string& t : a->texture_files) comments += "comment TextureFile " + t + "\n";
  std::string face_props = "property list uchar int vertex_indices\n";
  if (corner_uv) face_props += "property list uchar double texcoord\n";
  if (textures) face_props += "property int texnumber\n";
  w.text(std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") + " 1.0\n" + comments +
         "element vertex " + std::to_string(vertices.size()) + "\n" + props + "element face " +
         std::to_string(faces.size()) + "\n" + face_props + "end_header\n");
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const Vec3& p = vertices[v];
    if (binary) {
      w.binary_le(p[0]);
      w.binary_le(p[1]);
      w.binary_le(p[2]);
      for (int c = 0; c < channels; ++c) {
        if (uchar)
          w.binary_le(static_cast<uint8_t>(std::lround(a->colors[v][c] * 255.0)));
        else
          w.binary_le(a->colors[v][c]);
      }
      if (uv) {
        w.binary_le(a->texcoords[v][0]);
        w.binary_le(a->texcoords[v][1]);
      }
    } else {
      write_vec(w, p);
      for (int c = 0; c < channels; ++c) {
        w.text(" ");
        if (uchar)
          w.integer(std::lround(a->colors[v][c] * 255.0));
        else
          w.number(a->colors[v][c]);
      }
      if (uv) {
        w.text(" ");
        w.number(a->texcoords[v][0]);
        w.text(" ");
        w.number(a->texcoords[v][1]);
      }
      w.text("\n");
    }
    w.maybe_flush();
  }
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const F& f = faces[j];
    if (binary) {
      w.binary_le(static_cast<uint8_t>(f.size()));  // at most 255 corners: checked by the caller
      for (int i : f) w.binary_le(static_cast<int32_t>(i));
      if (corner_uv) {
        w.binary_le(static_cast<uint8_t>(6));
        for (int c = 0; c < 3; ++c) {
          w.binary_le(a->corner_uv[a->corner_uv_index[j][c]][0]);
          w.binary_le(a->corner_uv[a->corner_uv_index[j][c]][1]);
        }
      }
      if (textures) w.binary_le(static_cast<int32_t>(a->face_textures[j]));
    } else {
      write_face_corners(w, f);
      if (corner_uv) {
        w.text(" 6");
        for (int c = 0; c < 3; ++c) {
          w.text(" ");
          w.number(a->corner_uv[a->corner_uv_index[j][c]][0]);
          w.text(" ");
          w.number(a->corner_uv[a->corner_uv_index[j][c]][1]);
        }
      }
      if (textures) {
        w.text(" ");
        w.integer(a->face_textures[j]);
      }
      w.text("\n");
    }
    w.maybe_flush();
  }
}

Vec3 unit_normal(const TriMesh& m, const Face& f) {
  const Vec3 n = triangle_area_normal(m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]);
  const double len = n.norm();
  return len > 0.0 ? Vec3(n / len) : Vec3::Zero();
}

void write_stl(const TriMesh& m, ChunkedWriter& w, bool binary) {
  if (!binary) {
    w.text("solid strata\n");
    for (const Face& f : m.faces) {
      w.text("  facet normal ");
      write_vec(w, unit_normal(m, f));
      w.text("\n    outer loop\n");
      for (int i : f) {
        w.text("      vertex ");
        write_vec(w, m.vertices[i]);
        w.text("\n");
      }
      w.text("    endloop\n  endfacet\n");
      w.maybe_flush();
    }
    w.text("endsolid strata\n");
    return;
  }
  std::string header = "Strata binary STL";  // must not start with "solid" (that marks ASCII STL)
  header.resize(80, ' ');
  w.text(header);
  w.binary_le(static_cast<uint32_t>(m.faces.size()));
  for (const Face& f : m.faces) {
    const Vec3 n = unit_normal(m, f);
    for (int c = 0; c < 3; ++c) w.binary_le(static_cast<float>(n[c]));
    for (int i : f)
      for (int c = 0; c < 3; ++c) w.binary_le(static_cast<float>(m.vertices[i][c]));
    w.binary_le(static_cast<uint16_t>(0));
    w.maybe_flush();
  }
}

//! \p x rounded to float32. The volatile forces the conversion: GCC 12.2 at -O2 miscompiles
//! pairs of double->float->double casts into plain copies (SLP vectorizer), e.g. in
//! Eigen's v.cast<float>().cast<double>().
double round_to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

//! The mesh a reader will get back from an STL file written from \p mesh: welded corners,
//! rounded to float32 for binary STL.
TriMesh stl_image(const TriMesh& mesh, const std::string& name, bool binary) {
  Welder welder(name);
  TriMesh out;
  out.faces.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) {
    Face g;
    for (int c = 0; c < 3; ++c) {
      Vec3 p = mesh.vertices[f[c]];
      if (binary)
        for (int k = 0; k < 3; ++k) p[k] = round_to_float(p[k]);
      g[c] = static_cast<int>(welder.index_of(p));
    }
    out.faces.push_back(g);
  }
  out.vertices = std::move(welder.vertices());
  return out;
}

}  // namespace

std::vector<std::string> supported_mesh_extensions() {
  return {".obj", ".off", ".ply", ".stl"};
}

void validate_mesh(const TriMesh& mesh, const std::string& name) {
  const std::string problem = find_mesh_problem(mesh);
  if (!problem.empty()) fail_input(name.empty() ? std::string("mesh") : name, problem);
}

namespace {

TriMesh read_mesh_impl(const std::string& path, const ReadOptions& options,
                       std::vector<std::vector<int>>* polygons, int* flipped_faces,
                       MeshAttributes* attributes, std::vector<std::string>* dropped) {
  if (flipped_faces) *flipped_faces = 0;
  const Format format = format_of(path);
  const std::string file = internal::read_whole_file(path);
  // A UTF-8 byte order mark, as some Windows editors write, starts no keyword: skipped in the
  // text formats (a binary STL's header may hold any bytes; read_stl() skips it if ascii).
  std::string_view data = file;
  if (format != Format::Stl && data.substr(0, 3) == kUtf8Bom) data.remove_prefix(3);
  FaceRecord record;
  record.polygons = polygons;
  record.attributes = attributes;
  record.dropped = dropped;
  if (polygons) polygons->clear();
  TriMesh mesh;
  switch (format) {
    case Format::Obj:
      mesh = read_obj(path, data, &record);
      break;
    case Format::Off:
      mesh = read_off(path, data, &record);
      break;
    case Format::Ply:
      mesh = read_ply(path, data, &record);
      break;
    case Format::Stl:
      mesh = read_stl(path, data);
      if (polygons)
        for (const Face& f : mesh.faces) polygons->push_back({f[0], f[1], f[2]});
      break;
  }
  if (options.orient_faces) {
    const bool corner_data = attributes && !attributes->corner_uv_index.empty();
    const std::vector<Face> before = polygons || corner_data ? mesh.faces : std::vector<Face>{};
    int flipped = 0;
    try {
      flipped = orient_faces(mesh);
    } catch (const InvalidInput& e) {
      fail_input(path, e.what());
    }
    if (flipped_faces) *flipped_faces = flipped;
    // A flipped triangle's last two corners swapped places (orient_faces()): so do their texture
    // coordinates.
    if (corner_data && flipped > 0)
      for (std::size_t f = 0; f < mesh.faces.size(); ++f)
        if (mesh.faces[f] != before[f])
          std::swap(attributes->corner_uv_index[f][1], attributes->corner_uv_index[f][2]);
    // A flipped triangle's polygon runs the other way too (all of its triangles flip together in
    // a consistent part, the polygon's fan or clipping being oriented as the polygon).
    if (polygons && flipped > 0) {
      std::size_t tri = 0;
      for (std::vector<int>& poly : *polygons) {
        if (tri < mesh.faces.size() && mesh.faces[tri] != before[tri]) std::reverse(poly.begin(), poly.end());
        tri += poly.size() >= 3 ? poly.size() - 2 : 0;
      }
    }
  }
  long long face = -1;
  const std::string problem = find_mesh_problem(mesh, &face);
  if (!problem.empty()) fail_input(path, problem + file_face_note(face, record.cuts));
  return mesh;
}

}  // namespace

TriMesh read_mesh(const std::string& path) {
  return read_mesh(path, nullptr);
}

TriMesh read_mesh(const std::string& path, std::vector<std::vector<int>>* polygons) {
  return read_mesh(path, ReadOptions{}, polygons, nullptr);
}

TriMesh read_mesh(const std::string& path, const ReadOptions& options,
                  std::vector<std::vector<int>>* polygons, int* flipped_faces) {
  return read_mesh_impl(path, options, polygons, flipped_faces, nullptr, nullptr);
}

MeshFile read_mesh_file(const std::string& path, const ReadOptions& options) {
  MeshFile f;
  f.mesh = read_mesh_impl(path, options, &f.polygons, &f.flipped_faces, &f.attributes, &f.dropped);
  check_mesh_attributes(f.attributes, f.mesh, path);
  return f;
}

std::vector<std::string> attributes_not_stored(const MeshAttributes& attributes, const std::string& path) {
  const Format format = format_of(path);
  const MeshAttributes& a = attributes;
  const bool seams = !a.corner_uv_index.empty(),
             materials = !a.face_materials.empty() || !a.material_library.empty(),
             images = !a.texture_files.empty() || !a.face_textures.empty();
  std::vector<std::string> lost;
  if (format == Format::Stl) {
    if (!a.colors.empty()) lost.push_back("vertex colours");
    if (!a.texcoords.empty()) lost.push_back("texture coordinates");
  }
  if (seams && (format == Format::Off || format == Format::Stl))
    lost.push_back("texture coordinates per face corner (texture seams)");
  if (materials && format != Format::Obj)
    lost.push_back(format == Format::Ply && !a.texture_files.empty()
                       ? "materials (their diffuse images are kept, as TextureFile)"
                       : "materials");
  if (images && format != Format::Ply) lost.push_back("texture images (PLY's TextureFile)");
  return lost;
}

void write_mesh(const TriMesh& mesh, const std::string& path, MeshEncoding encoding) {
  write_mesh(mesh, MeshAttributes{}, path, encoding);
}

void write_mesh(const TriMesh& mesh, const MeshAttributes& attributes, const std::string& path,
                MeshEncoding encoding) {
  const Format format = format_of(path);
  check_mesh_attributes(attributes, mesh, path);
  const MeshAttributes* a = attributes.empty() ? nullptr : &attributes;
  // A name ends its line in OBJ, where a last '\' continues the line (read_obj()).
  if (format == Format::Obj) {
    auto check_end = [&](const std::string& name, const char* which) {
      if (!name.empty() && name.back() == '\\')
        fail_input(path, std::string(which) + " " + quote_token(name) +
                             " cannot be written to OBJ as it is (a '\\' at the end of a line continues it)");
    };
    check_end(attributes.material_library, "material library");
    for (const std::string& n : attributes.material_names) check_end(n, "material name");
  }
  if (encoding == MeshEncoding::Binary && (format == Format::Obj || format == Format::Off))
    fail_input(path, "OBJ and OFF have no binary encoding");
  validate_mesh(mesh, path);
  const bool binary = encoding != MeshEncoding::Ascii;  // Default is binary where a binary form exists
  if (format == Format::Stl) {
    // STL cannot store a vertex list; refuse rather than write a file that reads back different.
    if (binary)
      for (const Face& f : mesh.faces)  // unreferenced vertices are not written
        for (int v : f)
          if (mesh.vertices[v].cwiseAbs().maxCoeff() > static_cast<double>(std::numeric_limits<float>::max()))
            fail_input(
                path, "vertex " + std::to_string(v) + " has a coordinate too large for binary STL (float32)");
    const std::string problem = find_mesh_problem(stl_image(mesh, path, binary));
    if (!problem.empty())
      fail_input(path,
                 "cannot be stored as STL without changing it: once corners at equal positions are merged" +
                     std::string(binary ? " (after rounding to float32)" : "") + ", " + problem);
  }
  write_file_atomically(path, [&](const std::string& tmp) {
    ChunkedWriter w(path, tmp);
    switch (format) {
      case Format::Obj:
        write_obj(mesh.vertices, mesh.faces, w, a);
        break;
      case Format::Off:
        write_off(mesh.vertices, mesh.faces, w, a);
        break;
      case Format::Ply:
        write_ply(mesh.vertices, mesh.faces, w, binary, a);
        break;
      case Format::Stl:
        write_stl(mesh, w, binary);
        break;
    }
    w.close();
  });
}

void write_polygon_mesh(const std::vector<Vec3>& vertices, const std::vector<std::vector<int>>& polygons,
                        const std::string& path, MeshEncoding encoding) {
  const Format format = format_of(path);
  if (encoding == MeshEncoding::Binary && (format == Format::Obj || format == Format::Off))
    fail_input(path, "OBJ and OFF have no binary encoding");
  // The triangles read_mesh would make of these polygons must pass validation.
  TriMesh tri;
  tri.vertices = vertices;
  const long long nv = static_cast<long long>(vertices.size());
  FaceBuilder builder(path, nv, 0);
  std::vector<long long> corners;
  bool all_triangles = true;
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    const auto& f = polygons[k];
    if (f.size() > 255 && format == Format::Ply)
      fail_input(path, "face " + std::to_string(k) + " has " + std::to_string(f.size()) +
                           " corners; PLY stores at most 255");
    all_triangles = all_triangles && f.size() == 3;
    corners.assign(f.begin(), f.end());
    builder.add_checked(corners, [&] { return "face " + std::to_string(k); });
  }
  tri.faces = builder.finish(vertices);
  if (format == Format::Stl) {
    if (!all_triangles) fail_input(path, "STL stores triangles only; write polygons as OBJ, OFF or PLY");
    write_mesh(tri, path, encoding);
    return;
  }
  validate_mesh(tri, path);
  const bool binary = encoding != MeshEncoding::Ascii;
  write_file_atomically(path, [&](const std::string& tmp) {
    ChunkedWriter w(path, tmp);
    switch (format) {
      case Format::Obj:
        write_obj(vertices, polygons, w);
        break;
      case Format::Off:
        write_off(vertices, polygons, w);
        break;
      case Format::Ply:
        write_ply(vertices, polygons, w, binary);
        break;
      case Format::Stl:
        break;  // handled above
    }
    w.close();
  });
}

}  // namespace strata
