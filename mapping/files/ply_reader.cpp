#include "mapping/files/ply_reader.h"
#include "mapping/core/message_text.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "mapping/core/error.h"
#include "mapping/io/text_list.h"

namespace vdmap {
namespace {

enum class Format { kAscii, kBinaryLittle, kBinaryBig };

struct Property {
  std::string name;
  std::string type;        // scalar type, or the item type of a list
  std::string count_type;  // non-empty for lists
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  std::vector<double> scalars;                   // count x (number of scalar properties)
  std::vector<std::vector<std::int64_t>> lists;  // first list property only (faces)
  int scalarIndex(const std::string& prop) const {
    int k = 0;
    for (const auto& p : properties) {
      if (p.count_type.empty()) {
        if (p.name == prop) return k;
        ++k;
      }
    }
    return -1;
  }
  int scalarCount() const {
    return static_cast<int>(
        std::count_if(properties.begin(), properties.end(), [](const Property& p) { return p.count_type.empty(); }));
  }
};

int typeSize(const std::string& t) {
  static const std::map<std::string, int> sizes = {{"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},
                                                   {"short", 2}, {"ushort", 2},  {"int16", 2},  {"uint16", 2},
                                                   {"int", 4},   {"uint", 4},    {"int32", 4},  {"uint32", 4},
                                                   {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(t);
  return it == sizes.end() ? 0 : it->second;
}

bool isFloatType(const std::string& t) { return t == "float" || t == "float32" || t == "double" || t == "float64"; }

class Reader {
 public:
  explicit Reader(const std::filesystem::path& file) : file_(file), in_(file, std::ios::binary) {
    checkNotAFolder(file);
    if (!in_) throw InputError(file.string(), "cannot open the file");
  }

  std::vector<Element> read() {
    open();
    for (Element& e : elements_) readElement(e, true);
    return std::move(elements_);
  }

  /// Reads and checks the header; the elements' data follow.
  void open() {
    readHeader();
    checkElementSizes();
  }
  std::vector<Element>& elements() { return elements_; }

  /// Reads all of `e`'s records, keeping them in `e` or (keep false) checking and dropping them.
  void readElement(Element& e, bool keep) {
    if (keep) e.scalars.reserve(e.count * e.scalarCount());
    std::vector<double> row;
    for (std::size_t i = 0; i < e.count; ++i) {
      row.clear();
      readRecord(e, &row, keep ? &e.lists : nullptr);
      if (keep) e.scalars.insert(e.scalars.end(), row.begin(), row.end());
    }
  }

  /// Appends one record's scalars to `scalars` and its first list to `lists` (when given).
  void readRecord(const Element& e, std::vector<double>* scalars, std::vector<std::vector<std::int64_t>>* lists) {
    bool list_taken = false;
    for (const Property& p : e.properties) {
      if (p.count_type.empty()) {
        scalars->push_back(readScalar(p.type));
        continue;
      }
      const double n = readScalar(p.count_type);
      if (n < 0 || n > 1e6) fail("element " + printable(e.name) + " has a list of " + std::to_string(n) + " items");
      std::vector<std::int64_t> items(static_cast<std::size_t>(n));
      for (auto& item : items) {
        const double v = readScalar(p.type);
        if (!(std::abs(v) < 9e18))
          fail("element " + printable(e.name) + " has a list item out of range (" + std::to_string(v) + ")");
        item = static_cast<std::int64_t>(v);
      }
      if (lists && !list_taken) lists->push_back(std::move(items));
      list_taken = true;
    }
  }

 private:
  [[noreturn]] void fail(const std::string& what, int line = 0) const {
    if (line > 0) throw InputError(file_.string(), line, what);
    throw InputError(file_.string(), what);
  }

  void readHeader() {
    std::string line;
    int n = 0;
    bool format_seen = false;
    while (std::getline(in_, line)) {
      ++n;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream words(line);
      std::string key;
      words >> key;
      if (n == 1) {
        if (key != "ply") fail("not a PLY file (expected 'ply' on the first line)", 1);
        continue;
      }
      if (key == "format") {
        std::string f;
        words >> f;
        if (f == "ascii") format_ = Format::kAscii;
        else if (f == "binary_little_endian") format_ = Format::kBinaryLittle;
        else if (f == "binary_big_endian") format_ = Format::kBinaryBig;
        else fail("unknown format " + printable(f) + " (expected ascii, binary_little_endian or binary_big_endian)", n);
        format_seen = true;
      } else if (key == "element") {
        Element e;
        long long count = -1;
        words >> e.name >> count;
        if (e.name.empty() || count < 0) fail("expected 'element NAME COUNT'", n);
        e.count = static_cast<std::size_t>(count);
        elements_.push_back(std::move(e));
      } else if (key == "property") {
        if (elements_.empty()) fail("property before any element", n);
        Property p;
        std::string type;
        words >> type;
        if (type == "list") words >> p.count_type >> p.type >> p.name;
        else {
          p.type = type;
          words >> p.name;
        }
        if (p.name.empty() || typeSize(p.type) == 0 || (!p.count_type.empty() && typeSize(p.count_type) == 0))
          fail("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME' with a known type", n);
        elements_.back().properties.push_back(p);
      } else if (key == "end_header") {
        if (!format_seen) fail("header has no 'format' line", n);
        return;
      } else if (key != "comment" && key != "obj_info" && !key.empty()) {
        fail("unexpected header line " + printable(line), n);
      }
    }
    fail("header does not end with 'end_header' (" + counted(n, "line") + " read)");
  }

  // A header may claim any number of records: reject counts the rest of the file cannot hold
  // before anything is allocated or looped over.
  void checkElementSizes() {
    const std::streampos data = in_.tellg();
    in_.seekg(0, std::ios::end);
    const auto bytes = static_cast<std::uint64_t>(in_.tellg() - data);
    in_.seekg(data);
    for (const Element& e : elements_) {
      if (e.count == 0) continue;
      if (e.properties.empty()) fail("element " + printable(e.name) + " has no properties");
      std::uint64_t record = 0;  // the fewest bytes one record takes
      for (const Property& p : e.properties)
        record += format_ != Format::kAscii ? typeSize(p.count_type.empty() ? p.type : p.count_type) : 1;
      if (e.count > bytes / record)
        fail("element " + printable(e.name) + " has " + counted(static_cast<long long>(e.count), "record") +
             " but only " + counted(static_cast<long long>(bytes), "byte") + " follow the header (truncated?)");
    }
  }

  double readScalar(const std::string& type) {
    if (format_ == Format::kAscii) {
      double v;
      if (!(in_ >> v)) fail("file is truncated or has a non-number in element data");
      return v;
    }
    unsigned char bytes[8];
    const int size = typeSize(type);
    if (!in_.read(reinterpret_cast<char*>(bytes), size)) fail("file is truncated (binary data ends early)");
    const bool swap = (format_ == Format::kBinaryBig) == (std::endian::native == std::endian::little);
    if (swap) std::reverse(bytes, bytes + size);
    auto as = [&bytes]<typename T>(T) {
      T v;
      std::memcpy(&v, bytes, sizeof(T));
      return static_cast<double>(v);
    };
    if (type == "char" || type == "int8") return as(std::int8_t{});
    if (type == "uchar" || type == "uint8") return as(std::uint8_t{});
    if (type == "short" || type == "int16") return as(std::int16_t{});
    if (type == "ushort" || type == "uint16") return as(std::uint16_t{});
    if (type == "int" || type == "int32") return as(std::int32_t{});
    if (type == "uint" || type == "uint32") return as(std::uint32_t{});
    const double v = type == "float" || type == "float32" ? as(float{}) : as(double{});
    if (!std::isfinite(v)) fail("element data has a value that is not finite (NaN or infinity)");
    return v;
  }

  std::filesystem::path file_;
  std::ifstream in_;
  Format format_ = Format::kAscii;
  std::vector<Element> elements_;
};

const Element* findElement(const std::vector<Element>& elements, const std::string& name) {
  for (const auto& e : elements)
    if (e.name == name) return &e;
  return nullptr;
}

// Column indices of `names` in `e`; throws naming the first missing one.
std::vector<int> columns(const std::filesystem::path& file, const Element& e, const std::vector<std::string>& names,
                         const std::string& what) {
  std::vector<int> cols;
  for (const auto& n : names) {
    const int c = e.scalarIndex(n);
    if (c < 0) throw InputError(file.string(), printable(e.name) + " has no property '" + n + "' (" + what + ")");
    cols.push_back(c);
  }
  return cols;
}

std::vector<std::array<std::uint8_t, 3>> readColors(const std::filesystem::path& file, const Element& v) {
  const std::vector<int> c = columns(file, v, {"red", "green", "blue"}, "the file has no vertex colours");
  const bool unit = isFloatType(
      std::find_if(v.properties.begin(), v.properties.end(), [](const Property& p) { return p.name == "red"; })->type);
  const int stride = v.scalarCount();
  std::vector<std::array<std::uint8_t, 3>> colors(v.count);
  for (std::size_t i = 0; i < v.count; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = v.scalars[i * stride + c[k]] * (unit ? 255.0 : 1.0);
      colors[i][k] = static_cast<std::uint8_t>(std::clamp(x + (unit ? 0.5 : 0.0), 0.0, 255.0));
    }
  return colors;
}

std::vector<Eigen::Vector3f> readPositions(const std::filesystem::path& file, const Element& v) {
  const std::vector<int> c = columns(file, v, {"x", "y", "z"}, "positions are required");
  const int stride = v.scalarCount();
  std::vector<Eigen::Vector3f> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i)
    out[i] = Eigen::Vector3f(v.scalars[i * stride + c[0]], v.scalars[i * stride + c[1]], v.scalars[i * stride + c[2]]);
  return out;
}

const Element& vertexElement(const std::filesystem::path& file, const std::vector<Element>& elements) {
  const Element* v = findElement(elements, "vertex");
  if (!v) throw InputError(file.string(), "no 'vertex' element");
  return *v;
}

int indexOf(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

}  // namespace

ColoredTriangleMesh readPlyMesh(const std::filesystem::path& file) {
  const std::vector<Element> elements = Reader(file).read();
  const Element& v = vertexElement(file, elements);
  ColoredTriangleMesh mesh;
  mesh.positions = readPositions(file, v);
  mesh.colors = readColors(file, v);
  const Element* f = findElement(elements, "face");
  if (!f || f->count == 0 || f->lists.empty())
    throw InputError(file.string(), "the mesh has no faces (expected 'element face N' with a vertex_indices list)");
  for (const auto& poly : f->lists) {
    for (const auto idx : poly)
      if (idx < 0 || static_cast<std::size_t>(idx) >= mesh.positions.size())
        throw InputError(file.string(), "a face indexes vertex " + std::to_string(idx) + " of " +
                                            std::to_string(mesh.positions.size()));
    for (std::size_t k = 2; k < poly.size(); ++k)
      mesh.triangles.push_back({static_cast<std::uint32_t>(poly[0]), static_cast<std::uint32_t>(poly[k - 1]),
                                static_cast<std::uint32_t>(poly[k])});
  }
  if (mesh.triangles.empty())
    throw InputError(file.string(), "the mesh has no triangles (all faces have < 3 vertices)");
  return mesh;
}

std::vector<Eigen::Vector3f> readPlyPoints(const std::filesystem::path& file) {
  const std::vector<Element> elements = Reader(file).read();
  return readPositions(file, vertexElement(file, elements));
}

std::vector<EllipsoidRecord> readPlyEllipsoids(const std::filesystem::path& file) {
  const std::vector<Element> elements = Reader(file).read();
  const Element& v = vertexElement(file, elements);
  const std::vector<Eigen::Vector3f> means = readPositions(file, v);
  const auto colors = readColors(file, v);
  const std::vector<int> c = columns(file, v, {"cxx", "cxy", "cxz", "cyy", "cyz", "czz"},
                                     "an ellipsoid PLY needs the covariance (docs/method.md 11)");
  const int count_col = v.scalarIndex("count"), kf_col = v.scalarIndex("keyframe");
  const int stride = v.scalarCount();
  std::vector<EllipsoidRecord> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    const double* row = &v.scalars[i * stride];
    EllipsoidRecord& e = out[i];
    e.mean = means[i];
    e.rgb = colors[i];
    e.cov << row[c[0]], row[c[1]], row[c[2]], row[c[1]], row[c[3]], row[c[4]], row[c[2]], row[c[4]], row[c[5]];
    if (count_col >= 0 && !(row[count_col] >= 0 && row[count_col] <= 4294967295.0))
      throw InputError(file.string(), "vertex " + std::to_string(i) + ": count must be within 0..2^32-1");
    if (kf_col >= 0 && !(row[kf_col] >= -2147483648.0 && row[kf_col] <= 2147483647.0))
      throw InputError(file.string(), "vertex " + std::to_string(i) + ": keyframe must be a 32-bit integer");
    e.count = count_col >= 0 ? static_cast<std::uint32_t>(row[count_col]) : 1u;
    e.keyframe = kf_col >= 0 ? static_cast<std::int32_t>(row[kf_col]) : 0;
  }
  return out;
}

int PlyVertexTable::column(const std::string& name) const { return indexOf(names, name); }

struct PlyVertexReader::State {
  explicit State(const std::filesystem::path& file) : reader(file) {}
  Reader reader;
  std::size_t vertex = 0;  // index of the vertex element
  std::vector<double> row;
};

PlyVertexReader::PlyVertexReader(const std::filesystem::path& file) : state_(std::make_unique<State>(file)) {
  Reader& r = state_->reader;
  r.open();
  std::vector<Element>& elements = r.elements();
  const Element& v = vertexElement(file, elements);
  state_->vertex = static_cast<std::size_t>(&v - elements.data());
  for (const Property& p : v.properties)
    if (p.count_type.empty()) names_.push_back(p.name);
  count_ = v.count;
  for (std::size_t e = 0; e < state_->vertex; ++e) r.readElement(elements[e], false);
}

PlyVertexReader::~PlyVertexReader() = default;

int PlyVertexReader::column(const std::string& name) const { return indexOf(names_, name); }

const std::vector<double>& PlyVertexReader::row() const { return state_->row; }

bool PlyVertexReader::next() {
  std::vector<Element>& elements = state_->reader.elements();
  if (read_ < count_) {
    state_->row.clear();
    state_->reader.readRecord(elements[state_->vertex], &state_->row, nullptr);
    ++read_;
    return true;
  }
  if (!rest_checked_) {  // what follows the vertices is checked as readPlyVertices checks it
    for (std::size_t e = state_->vertex + 1; e < elements.size(); ++e) state_->reader.readElement(elements[e], false);
    rest_checked_ = true;
  }
  return false;
}

PlyVertexTable readPlyVertices(const std::filesystem::path& file) {
  PlyVertexReader reader(file);
  PlyVertexTable table;
  table.names = reader.names();
  table.count = reader.count();
  table.values.reserve(table.count * table.names.size());
  while (reader.next()) table.values.insert(table.values.end(), reader.row().begin(), reader.row().end());
  return table;
}

}  // namespace vdmap
