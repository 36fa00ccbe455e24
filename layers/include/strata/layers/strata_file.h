//! \file strata_file.h
//! The `.strata` container: a versioned file of one JSON header and named little-endian binary
//! sections, each with a CRC-32. LayeredModel (model.h) stores itself in it; this layer knows
//! nothing of bands and only guarantees that what is read is exactly what was written, or an
//! error that names the file and the problem. The byte layout is documented in layers/FORMAT.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace strata::layers {

//! The container format version this code writes; it reads versions 1 .. this one.
constexpr std::uint32_t kStrataFormatVersion = 1;

//! One named binary section: raw little-endian bytes (see the pack/unpack helpers below).
struct Section {
  std::string name;  //!< unique within a file, 1 to 64 printable ASCII characters
  std::vector<std::uint8_t> bytes;
};

//! A container's contents: the caller's JSON header (an object, stored under the key "model" of
//! the file's own header) and its sections, in file order.
//! read_strata_container returns model_json as the compact serialization of the JSON value that
//! was written (same value, same key order, no whitespace), not necessarily the caller's exact
//! text; numbers keep their exact value (doubles are written with round-trip precision).
struct StrataContainer {
  std::string model_json = "{}";
  std::vector<Section> sections;

  //! The section called \p name, or nullptr.
  const Section* find(const std::string& name) const;
  //! The section called \p name.
  //! \throw InvalidInput "<file>: missing section '<name>'" (\p file names the file in the message).
  const Section& require(const std::string& name, const std::string& file) const;
};

//! Writes \p container to \p path atomically (write_file_atomically: a temporary file, then a
//! rename; on any error \p path is left as it was).
//! \throw InvalidInput if model_json is not a JSON object (or nests deeper than 256 levels, or has
//!        an object of more than 1024 keys or with a key twice: json_structure_problem()), or a
//!        section name is empty, too long, not printable ASCII, or repeated. Nothing is written then.
//! \throw IoError if the file cannot be written.
void write_strata_container(const StrataContainer& container, const std::string& path);

//! Reads and checks a container: the magic, the format version, the header's and every
//! section's CRC-32, the section table (in range, in order, not overlapping) and the file's exact
//! length. Never reads beyond the file, and sizes no allocation from a number it has not checked
//! against the file's length. The file's bytes and its sections take about twice the file's size;
//! the parsed JSON header can take tens of times the header's length (layers/FORMAT.md).
//! \throw IoError "<path>: <problem>" if the file cannot be opened or read, is not a Strata file
//!        (wrong magic), was written by a newer format version, is truncated, has trailing bytes,
//!        a corrupted header or section (checksum mismatch, naming the section), or a malformed
//!        header or section table.
StrataContainer read_strata_container(const std::string& path);

// Little-endian packing of flat arrays into section bytes, and back. The unpackers check that
// the byte count is a whole number of elements and, when \p expected_count >= 0, that it holds
// exactly that many; they throw InvalidInput "<what>: <problem>" otherwise.
std::vector<std::uint8_t> pack_f64(const std::vector<double>& values);
std::vector<std::uint8_t> pack_i32(const std::vector<std::int32_t>& values);
std::vector<double> unpack_f64(const Section& section, long long expected_count, const std::string& what);
std::vector<std::int32_t> unpack_i32(const Section& section, long long expected_count,
                                     const std::string& what);

}  // namespace strata::layers
