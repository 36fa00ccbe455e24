// The .strata container: see strata_file.h for the contract and layers/FORMAT.md for the bytes.
#include "strata/layers/strata_file.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "strata/atomic_file.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"

namespace strata::layers {
namespace {

// ordered_json keeps the header's keys, and the caller's, in the order they were written.
using Json = nlohmann::ordered_json;

#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool kHostLittleEndian = true;
#elif defined(__BYTE_ORDER__) && defined(__ORDER_BIG_ENDIAN__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
constexpr bool kHostLittleEndian = false;
#elif defined(_WIN32)
constexpr bool kHostLittleEndian = true;
#else
#error "strata_file.cpp: cannot determine the host byte order"
#endif

constexpr unsigned char kMagic[8] = {0x89, 'S', 'T', 'R', 'A', 'T', 'A', 0x0A};
constexpr std::size_t kPrefixSize = 20;  // magic, version, header length, header CRC-32
constexpr std::size_t kAlignment = 8;
constexpr std::size_t kMaxNameLength = 64;

std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size) {
  uLong crc = ::crc32(0L, Z_NULL, 0);
  // zlib takes a 32-bit length; feed larger buffers in chunks.
  constexpr std::size_t kChunk = std::size_t{1} << 30;
  while (size > 0) {
    const std::size_t n = std::min(size, kChunk);
    crc = ::crc32(crc, data, static_cast<uInt>(n));
    data += n;
    size -= n;
  }
  return static_cast<std::uint32_t>(crc);
}

std::uint32_t crc32_of(const std::string& text) {
  return crc32_of(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

void put_u32(unsigned char* out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<unsigned char>((v >> (8 * i)) & 0xFFu);
}

std::uint32_t get_u32(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i)
    v = (v << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(i)]);
  return v;
}

std::uint64_t align_up(std::uint64_t x) {
  return (x + kAlignment - 1) / kAlignment * kAlignment;
}

//! Why \p name is not a valid section name, or "" if it is.
std::string name_problem(const std::string& name) {
  if (name.empty()) return "is empty";
  if (name.size() > kMaxNameLength)
    return "is " + std::to_string(name.size()) + " characters long (at most " +
           std::to_string(kMaxNameLength) + ")";
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7E)
      return "contains a character that is not printable ASCII (byte " + std::to_string(u) + ")";
  }
  return "";
}

//! Parses \p text; returns "" or, if it is outside the format's JsonLimits (too deep, an object
//! with too many keys or a key twice), the problem (\p out is then left unset; no value is
//! built). Throws nlohmann's exceptions on malformed JSON.
std::string parse_json_limited(const char* begin, const char* end, Json& out, const JsonLimits& limits = {}) {
  std::string problem =
      json_structure_problem(std::string_view(begin, static_cast<std::size_t>(end - begin)), limits);
  if (problem.empty()) out = Json::parse(begin, end);
  return problem;
}

//! The file-level header text of \p container, whose sections start \p first_offset bytes into
//! the file; \p model is the caller's parsed model JSON, \p crcs the sections' CRC-32s.
std::string header_text(const StrataContainer& container, const Json& model,
                        const std::vector<std::uint32_t>& crcs, std::uint64_t first_offset) {
  Json sections = Json::array();
  std::uint64_t offset = first_offset;
  for (std::size_t i = 0; i < container.sections.size(); ++i) {
    const Section& s = container.sections[i];
    offset = align_up(offset);
    Json entry = Json::object();
    entry["name"] = s.name;
    entry["offset"] = offset;
    entry["size"] = static_cast<std::uint64_t>(s.bytes.size());
    entry["crc32"] = crcs[i];
    sections.push_back(std::move(entry));
    offset += s.bytes.size();
  }
  Json header = Json::object();
  header["format"] = "strata";
  header["version"] = kStrataFormatVersion;
  header["sections"] = std::move(sections);
  header["model"] = model;
  return header.dump();
}

// ---- reading ------------------------------------------------------------------------------------

//! Reading one file: every error names the file.
class Reader {
 public:
  Reader(std::string path, std::string bytes) : path_(std::move(path)), bytes_(std::move(bytes)) {}

  StrataContainer read() {
    const std::size_t n = bytes_.size();
    check_prefix();
    const std::uint64_t header_length = get_u32(bytes_, 12);
    const std::uint32_t header_crc = get_u32(bytes_, 16);
    const std::uint64_t header_end = kPrefixSize + header_length;
    if (header_end > n)
      fail("truncated: the header ends at byte " + std::to_string(header_end) + ", file has " +
           std::to_string(n) + " bytes");
    const char* header_begin = bytes_.data() + kPrefixSize;
    if (crc32_of(reinterpret_cast<const std::uint8_t*>(header_begin), header_length) != header_crc)
      fail("header checksum mismatch (corrupted)");

    const Json header = parse_header(header_begin, header_begin + header_length);
    StrataContainer container;
    container.model_json = header["model"].dump();
    read_sections(header["sections"], header_end, container);
    return container;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const { throw IoError(path_ + ": " + problem); }
  [[noreturn]] void malformed(const std::string& problem) const { fail("malformed header: " + problem); }

  void check_prefix() const {
    const std::size_t n = bytes_.size();
    const std::size_t magic_bytes = std::min(n, sizeof kMagic);
    if (std::memcmp(bytes_.data(), kMagic, magic_bytes) != 0) fail("not a Strata model file (bad magic)");
    if (n < 12) {
      if (n == 0) fail("truncated: the file is empty (a Strata model file starts with a 20-byte prefix)");
      fail("truncated: file has " + std::to_string(n) + " bytes, the fixed prefix needs " +
           std::to_string(kPrefixSize));
    }
    const std::uint32_t version = get_u32(bytes_, 8);
    if (version == 0) fail("bad format version 0 (corrupted)");
    if (version > kStrataFormatVersion)
      fail("written by a newer Strata (format version " + std::to_string(version) +
           "; this build reads up to " + std::to_string(kStrataFormatVersion) + ")");
    if (n < kPrefixSize)
      fail("truncated: file has " + std::to_string(n) + " bytes, the fixed prefix needs " +
           std::to_string(kPrefixSize));
  }

  Json parse_header(const char* begin, const char* end) const {
    Json header;
    std::string problem;
    try {
      // The model object is at most 256 levels deep, as the writer checks it: the header around
      // it is one level more (a model of 256 was written and then refused).
      JsonLimits limits;
      limits.max_depth += 1;
      problem = parse_json_limited(begin, end, header, limits);
    } catch (const Json::exception& e) {
      malformed("invalid JSON: " + json_error_text(e.what()));
    }
    if (!problem.empty()) malformed(problem);
    if (!header.is_object()) malformed("not a JSON object");
    static const std::set<std::string> kKeys = {"format", "version", "sections", "model"};
    for (const std::string& key : kKeys)
      if (!header.contains(key)) malformed("missing key '" + key + "'");
    for (const auto& item : header.items())
      if (kKeys.count(item.key()) == 0) malformed("unknown key '" + printable_key(item.key()) + "'");
    if (!header["format"].is_string() || header["format"].get<std::string>() != "strata")
      malformed("'format' is not \"strata\"");
    const std::uint64_t version = unsigned_value(header["version"], "'version'");
    if (version != get_u32(bytes_, 8))
      malformed("'version' is " + std::to_string(version) + " but the file's format version is " +
                std::to_string(get_u32(bytes_, 8)));
    if (!header["sections"].is_array()) malformed("'sections' is not an array");
    if (!header["model"].is_object()) malformed("'model' is not a JSON object");
    return header;
  }

  //! \p value as a non-negative integer (not a float, not negative).
  std::uint64_t unsigned_value(const Json& value, const std::string& what) const {
    if (value.is_number_unsigned()) return value.get<std::uint64_t>();
    if (value.is_number_integer() && value.get<std::int64_t>() >= 0)
      return static_cast<std::uint64_t>(value.get<std::int64_t>());
    malformed(what + " is not a non-negative integer");
  }

  void read_sections(const Json& table, std::uint64_t header_end, StrataContainer& container) const {
    const std::uint64_t n = bytes_.size();
    std::set<std::string> names;
    std::uint64_t previous_end = header_end;
    std::string previous = "the header";
    for (std::size_t i = 0; i < table.size(); ++i) {
      const Json& entry = table[i];
      const std::string where = "section table entry " + std::to_string(i);
      if (!entry.is_object()) malformed(where + " is not an object");
      for (const char* key : {"name", "offset", "size", "crc32"})
        if (!entry.contains(key)) malformed(where + " has no '" + key + "'");
      if (entry.size() != 4) malformed(where + " has unknown keys");
      if (!entry["name"].is_string()) malformed(where + ": 'name' is not a string");
      const std::string name = entry["name"].get<std::string>();
      const std::string problem = name_problem(name);
      if (!problem.empty()) malformed(where + ": section name " + problem);
      const std::string quoted = "section '" + name + "'";
      if (!names.insert(name).second) malformed("duplicate " + quoted);
      const std::uint64_t offset = unsigned_value(entry["offset"], quoted + ": 'offset'");
      const std::uint64_t size = unsigned_value(entry["size"], quoted + ": 'size'");
      const std::uint64_t crc = unsigned_value(entry["crc32"], quoted + ": 'crc32'");
      if (crc > 0xFFFFFFFFu) malformed(quoted + ": 'crc32' does not fit in 32 bits");

      // Each section starts at the first 8-byte boundary after the previous one (or the header).
      if (offset < previous_end)
        malformed(quoted + " at byte " + std::to_string(offset) + " overlaps " + previous +
                  " (out of order or overlapping sections)");
      const std::uint64_t expected = align_up(previous_end);
      if (offset != expected)
        malformed(quoted + " starts at byte " + std::to_string(offset) + ", expected " +
                  std::to_string(expected) + " (the first 8-byte boundary after " + previous + ")");
      // offset <= n is checked first, so offset + size cannot overflow.
      if (offset > n || size > n - offset)
        fail("truncated: " + quoted + " ends at byte " +
             (size > std::numeric_limits<std::uint64_t>::max() - offset ? std::string("beyond 2^64")
                                                                        : std::to_string(offset + size)) +
             ", file has " + std::to_string(n) + " bytes");
      for (std::uint64_t b = previous_end; b < offset; ++b)
        if (bytes_[b] != 0)
          fail("nonzero padding byte " + std::to_string(b) + " before " + quoted + " (corrupted)");
      const auto* data = reinterpret_cast<const std::uint8_t*>(bytes_.data()) + offset;
      if (crc32_of(data, size) != crc) fail(quoted + " checksum mismatch (corrupted)");
      container.sections.push_back(Section{name, std::vector<std::uint8_t>(data, data + size)});
      previous_end = offset + size;
      previous = quoted;
    }
    if (previous_end < n)
      fail(std::to_string(n - previous_end) + " trailing bytes after " +
           (table.empty() ? std::string("the header (no sections)") : std::string("the last section")));
  }

  std::string path_;
  std::string bytes_;
};

// ---- packing ------------------------------------------------------------------------------------

template <typename T>
std::vector<std::uint8_t> pack_le(const std::vector<T>& values) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::uint8_t> bytes(values.size() * sizeof(T));
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  if constexpr (!kHostLittleEndian)
    for (std::size_t i = 0; i < bytes.size(); i += sizeof(T)) std::reverse(&bytes[i], &bytes[i] + sizeof(T));
  return bytes;
}

template <typename T>
std::vector<T> unpack_le(const Section& section, long long expected_count, const std::string& what) {
  const std::size_t size = section.bytes.size();
  if (size % sizeof(T) != 0)
    throw InvalidInput(what + ": section '" + section.name + "' has " + std::to_string(size) +
                       " bytes, not a whole number of " + std::to_string(sizeof(T)) + "-byte values");
  const std::size_t count = size / sizeof(T);
  if (expected_count >= 0 && count != static_cast<unsigned long long>(expected_count))
    throw InvalidInput(what + ": section '" + section.name + "' holds " + std::to_string(count) +
                       " values, expected " + std::to_string(expected_count));
  std::vector<T> values(count);
  if (count == 0) return values;
  if constexpr (kHostLittleEndian) {
    std::memcpy(values.data(), section.bytes.data(), size);
  } else {
    std::vector<std::uint8_t> swapped(section.bytes);
    for (std::size_t i = 0; i < size; i += sizeof(T)) std::reverse(&swapped[i], &swapped[i] + sizeof(T));
    std::memcpy(values.data(), swapped.data(), size);
  }
  return values;
}

}  // namespace

const Section* StrataContainer::find(const std::string& name) const {
  for (const Section& s : sections)
    if (s.name == name) return &s;
  return nullptr;
}

const Section& StrataContainer::require(const std::string& name, const std::string& file) const {
  const Section* s = find(name);
  if (s == nullptr) throw InvalidInput(file + ": missing section '" + name + "'");
  return *s;
}

void write_strata_container(const StrataContainer& container, const std::string& path) {
  // Validate everything before the target is touched.
  Json model;
  std::string problem;
  try {
    problem = parse_json_limited(container.model_json.data(),
                                 container.model_json.data() + container.model_json.size(), model);
  } catch (const Json::exception& e) {
    throw InvalidInput(path + ": model_json is not valid JSON: " + json_error_text(e.what()));
  }
  if (!problem.empty()) throw InvalidInput(path + ": model_json: " + problem);
  if (!model.is_object()) throw InvalidInput(path + ": model_json is not a JSON object");
  std::set<std::string> names;
  for (const Section& s : container.sections) {
    const std::string problem = name_problem(s.name);
    if (!problem.empty()) throw InvalidInput(path + ": section name '" + s.name + "' " + problem);
    if (!names.insert(s.name).second) throw InvalidInput(path + ": duplicate section name '" + s.name + "'");
  }

  // The section offsets depend on the header's length, which depends on the offsets' digits. The
  // length is nondecreasing in the assumed length, so iterating from the shortest converges.
  std::vector<std::uint32_t> crcs;
  for (const Section& s : container.sections) crcs.push_back(crc32_of(s.bytes.data(), s.bytes.size()));
  std::string header = header_text(container, model, crcs, kPrefixSize);
  for (;;) {
    const std::string next = header_text(container, model, crcs, kPrefixSize + header.size());
    if (next.size() == header.size()) {
      header = next;
      break;
    }
    header = next;
  }
  if (header.size() > std::numeric_limits<std::uint32_t>::max())
    throw InvalidInput(path + ": the header is " + std::to_string(header.size()) + " bytes, more than 4 GiB");

  unsigned char prefix[kPrefixSize];
  std::memcpy(prefix, kMagic, sizeof kMagic);
  put_u32(prefix + 8, kStrataFormatVersion);
  put_u32(prefix + 12, static_cast<std::uint32_t>(header.size()));
  put_u32(prefix + 16, crc32_of(header));

  write_file_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(path + ": cannot open temporary file " + tmp + " for writing");
    out.write(reinterpret_cast<const char*>(prefix), sizeof prefix);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    std::uint64_t position = kPrefixSize + header.size();
    static const char kZeros[kAlignment] = {};
    for (const Section& s : container.sections) {
      const std::uint64_t offset = align_up(position);
      out.write(kZeros, static_cast<std::streamsize>(offset - position));
      out.write(reinterpret_cast<const char*>(s.bytes.data()), static_cast<std::streamsize>(s.bytes.size()));
      position = offset + s.bytes.size();
    }
    out.close();
    if (!out) throw IoError(path + ": writing temporary file " + tmp + " failed (disk full?)");
  });
}

StrataContainer read_strata_container(const std::string& path) {
  return Reader(path, read_file_bytes(path)).read();
}

std::vector<std::uint8_t> pack_f64(const std::vector<double>& values) {
  return pack_le(values);
}
std::vector<std::uint8_t> pack_i32(const std::vector<std::int32_t>& values) {
  return pack_le(values);
}

std::vector<double> unpack_f64(const Section& section, long long expected_count, const std::string& what) {
  static_assert(sizeof(double) == 8 && std::numeric_limits<double>::is_iec559, "IEEE 754 doubles required");
  return unpack_le<double>(section, expected_count, what);
}

std::vector<std::int32_t> unpack_i32(const Section& section, long long expected_count,
                                     const std::string& what) {
  return unpack_le<std::int32_t>(section, expected_count, what);
}

}  // namespace strata::layers
