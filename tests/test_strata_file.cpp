// Tests for strata_file.h, the .strata container. The byte layout is checked against
// layers/FORMAT.md by an independent decoder and an independent writer below (their own CRC-32,
// their own little-endian code), so the tests do not trust the code under test to describe itself.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "strata/exceptions.h"
#include "strata/layers/strata_file.h"
#include "test_files.h"

namespace fs = std::filesystem;
using strata::InvalidInput;
using strata::IoError;
using namespace strata::layers;

namespace {

using Bytes = std::vector<std::uint8_t>;
using OJson = nlohmann::ordered_json;

// A JSON object of \p n keys "0", "1", ..., each with the value 0.
std::string many_keys(int n) {
  std::string s = "{";
  for (int k = 0; k < n; ++k) s += (k ? ",\"" : "\"") + std::to_string(k) + "\":0";
  return s + "}";
}

// ---------------------------------------------------------------------------------------------
// Helpers independent of the code under test

Bytes slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Writes a fresh file (removing any old one first: truncating a file ext4 has not flushed yet
// forces a flush, which made the many small writes below slow).
void spit(const std::string& path, const Bytes& bytes) {
  std::error_code ec;
  fs::remove(path, ec);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.close();
  ASSERT_TRUE(out.good()) << path;
}

//! Overwrites the byte at \p at of the existing file \p path in place.
void poke(const std::string& path, std::size_t at, std::uint8_t value) {
  std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
  f.seekp(static_cast<std::streamoff>(at));
  f.put(static_cast<char>(value));
  f.close();
  ASSERT_TRUE(f.good()) << path;
}

//! Bitwise CRC-32 (reflected, polynomial 0xEDB88320), as zlib computes it.
std::uint32_t reference_crc32(const std::uint8_t* data, std::size_t size) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}
std::uint32_t reference_crc32(const std::string& s) {
  return reference_crc32(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
}
std::uint32_t reference_crc32(const Bytes& b) {
  return reference_crc32(b.data(), b.size());
}

std::uint32_t le32(const Bytes& b, std::size_t at) {
  return std::uint32_t{b[at]} | std::uint32_t{b[at + 1]} << 8 | std::uint32_t{b[at + 2]} << 16 |
         std::uint32_t{b[at + 3]} << 24;
}
void put_le32(Bytes& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint64_t align8(std::uint64_t x) {
  return (x + 7) / 8 * 8;
}

const Bytes kMagic = {0x89, 'S', 'T', 'R', 'A', 'T', 'A', 0x0A};

//! A file built by hand after FORMAT.md: prefix, \p header text, then \p sections at the canonical
//! offsets with zero padding. The header's CRC-32 is correct unless \p header_crc is given.
Bytes hand_built_file(const std::string& header, const std::vector<Bytes>& sections,
                      std::uint32_t version = 1) {
  Bytes file = kMagic;
  file.resize(20);
  put_le32(file, 8, version);
  put_le32(file, 12, static_cast<std::uint32_t>(header.size()));
  put_le32(file, 16, reference_crc32(header));
  file.insert(file.end(), header.begin(), header.end());
  for (const Bytes& s : sections) {
    file.resize(align8(file.size()), 0);
    file.insert(file.end(), s.begin(), s.end());
  }
  return file;
}

//! The section table of a hand-built file whose header is \p header_without_table plus the table:
//! computes the canonical offsets, which depend on the header's own length, by iteration.
std::string hand_built_header(const std::vector<std::pair<std::string, Bytes>>& sections,
                              const OJson& model = OJson::object()) {
  std::size_t assumed = 0;
  for (;;) {
    OJson table = OJson::array();
    std::uint64_t pos = 20 + assumed;
    for (const auto& [name, bytes] : sections) {
      pos = align8(pos);
      table.push_back(
          {{"name", name}, {"offset", pos}, {"size", bytes.size()}, {"crc32", reference_crc32(bytes)}});
      pos += bytes.size();
    }
    const std::string text =
        OJson{{"format", "strata"}, {"version", 1}, {"sections", table}, {"model", model}}.dump();
    if (text.size() == assumed) return text;
    assumed = text.size();
  }
}

std::vector<Bytes> bytes_of(const std::vector<std::pair<std::string, Bytes>>& sections) {
  std::vector<Bytes> out;
  for (const auto& s : sections) out.push_back(s.second);
  return out;
}

//! Expects read_strata_container(\p path) to throw IoError whose message starts with the path and
//! contains \p needle; returns the message.
std::string expect_io_error(const std::string& path, const std::string& needle) {
  try {
    read_strata_container(path);
  } catch (const IoError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << "expected '" << needle << "' in: " << msg;
    return msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected IoError, got another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << path << ": expected IoError containing '" << needle << "', but the read succeeded";
  return "";
}

double from_bits(std::uint64_t bits) {
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}

//! A container with sections of every kind: odd sizes (so padding occurs), empty ones (first,
//! middle and last), doubles with NaN payloads, infinities, -0 and subnormals, extreme integers.
StrataContainer sample_container(std::mt19937_64& rng, std::size_t n_doubles = 61) {
  std::vector<double> doubles = {0.0,
                                 -0.0,
                                 std::numeric_limits<double>::infinity(),
                                 -std::numeric_limits<double>::infinity(),
                                 std::numeric_limits<double>::denorm_min(),
                                 std::numeric_limits<double>::max(),
                                 from_bits(0x7FF0000000000001ull),   // signalling NaN
                                 from_bits(0x7FF8DEADBEEF1234ull),   // quiet NaN with a payload
                                 from_bits(0xFFFFFFFFFFFFFFFFull)};  // negative NaN, all ones
  while (doubles.size() < n_doubles) doubles.push_back(from_bits(rng()));
  std::vector<std::int32_t> ints = {0, -1, std::numeric_limits<std::int32_t>::min(),
                                    std::numeric_limits<std::int32_t>::max()};
  for (int i = 0; i < 37; ++i) ints.push_back(static_cast<std::int32_t>(rng()));
  Bytes odd(13);
  for (auto& b : odd) b = static_cast<std::uint8_t>(rng());

  StrataContainer c;
  c.model_json =
      R"({"kind":"layered","bands":[{"level":0,"scale":0.1,"tags":["a","\u00e9\u4e2d"]},)"
      R"({"level":1,"nested":{"deep":[1,2,[3,{"x":null}]],"flag":true}}],"z":-1.5e-300,"a":18446744073709551615})";
  c.sections = {{"empty.first", {}},
                {"band0.positions", pack_f64(doubles)},
                {"odd bytes", odd},
                {"band0.faces", pack_i32(ints)},
                {"empty.middle", {}},
                {"three", {1, 2, 3}},
                {std::string(64, 'n'), pack_f64({1.0, 2.0})},
                {"empty.last", {}}};
  return c;
}

//! Decodes \p file after FORMAT.md and checks every rule of the layout; returns the section table.
OJson check_layout(const Bytes& file) {
  EXPECT_GE(file.size(), 20u);
  EXPECT_TRUE(std::equal(kMagic.begin(), kMagic.end(), file.begin()));
  EXPECT_EQ(le32(file, 8), 1u);
  const std::uint32_t h = le32(file, 12);
  EXPECT_LE(20u + h, file.size());
  const std::string header(file.begin() + 20, file.begin() + 20 + h);
  EXPECT_EQ(le32(file, 16), reference_crc32(header));
  const OJson j = OJson::parse(header);
  EXPECT_EQ(header, j.dump()) << "the header is compact JSON";
  EXPECT_EQ(std::vector<std::string>({"format", "version", "sections", "model"}), [&] {
    std::vector<std::string> keys;
    for (const auto& it : j.items()) keys.push_back(it.key());
    return keys;
  }());
  EXPECT_EQ(j["format"], "strata");
  EXPECT_EQ(j["version"], 1);
  std::uint64_t pos = 20 + h;
  for (const auto& s : j["sections"]) {
    const std::uint64_t offset = s["offset"], size = s["size"];
    EXPECT_EQ(offset, align8(pos)) << s.dump();
    for (std::uint64_t b = pos; b < offset; ++b) EXPECT_EQ(file[b], 0) << "padding byte " << b;
    EXPECT_LE(offset + size, file.size());
    const Bytes bytes(file.begin() + static_cast<std::ptrdiff_t>(offset),
                      file.begin() + static_cast<std::ptrdiff_t>(offset + size));
    EXPECT_EQ(s["crc32"].get<std::uint32_t>(), reference_crc32(bytes)) << s.dump();
    pos = offset + size;
  }
  EXPECT_EQ(pos, file.size()) << "the file ends exactly at the end of the last section";
  return j["sections"];
}

// ---------------------------------------------------------------------------------------------
// Writing and reading

TEST(StrataFile, ReferenceCrcIsZlibs) {
  // The check value of CRC-32 (zlib, PNG, gzip); guards the independent checker above.
  EXPECT_EQ(reference_crc32(std::string("123456789")), 0xCBF43926u);
  EXPECT_EQ(reference_crc32(std::string()), 0u);
}

TEST(StrataFile, RoundTripIsBitExact) {
  strata::test::ScratchDir dir{"strata_file"};
  std::mt19937_64 rng(20240501);
  const StrataContainer written = sample_container(rng);
  const std::string path = dir.file("model.strata");
  write_strata_container(written, path);

  const StrataContainer read = read_strata_container(path);
  ASSERT_EQ(read.sections.size(), written.sections.size());
  for (std::size_t i = 0; i < written.sections.size(); ++i) {
    EXPECT_EQ(read.sections[i].name, written.sections[i].name);
    EXPECT_EQ(read.sections[i].bytes, written.sections[i].bytes) << written.sections[i].name;
  }
  // The doubles come back with their exact bit patterns, NaN payloads included.
  const auto orig = unpack_f64(written.sections[1], -1, "orig");
  const auto back =
      unpack_f64(read.require("band0.positions", path), static_cast<long long>(orig.size()), "back");
  ASSERT_EQ(back.size(), orig.size());
  EXPECT_EQ(0, std::memcmp(back.data(), orig.data(), orig.size() * sizeof(double)));
  EXPECT_TRUE(std::isnan(back[6]) && std::isnan(back[7]) && std::isnan(back[8]));
  EXPECT_TRUE(std::signbit(back[1]));
  EXPECT_EQ(unpack_i32(read.sections[3], -1, "ints"), unpack_i32(written.sections[3], -1, "ints"));

  // The model comes back as the same JSON value, keys in the order written, compact.
  EXPECT_EQ(OJson::parse(read.model_json), OJson::parse(written.model_json));
  EXPECT_EQ(read.model_json, OJson::parse(written.model_json).dump());

  // The file is exactly what FORMAT.md describes, down to its length.
  const Bytes file = slurp(path);
  const OJson table = check_layout(file);
  ASSERT_EQ(table.size(), written.sections.size());
  std::uint64_t predicted = 20 + le32(file, 12);
  for (const Section& s : written.sections) predicted = align8(predicted) + s.bytes.size();
  EXPECT_EQ(file.size(), predicted);
  EXPECT_EQ(dir.listing(), std::set<std::string>{"model.strata"}) << "no temporary file left behind";
}

TEST(StrataFile, EmptyContainerEndsAtTheHeader) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string path = dir.file("empty.strata");
  write_strata_container(StrataContainer{}, path);
  const Bytes file = slurp(path);
  check_layout(file);
  EXPECT_EQ(file.size(), 20u + le32(file, 12));
  const StrataContainer read = read_strata_container(path);
  EXPECT_TRUE(read.sections.empty());
  EXPECT_EQ(read.model_json, "{}");
}

TEST(StrataFile, FormatMdExampleIsExact) {
  // The worked example of layers/FORMAT.md, byte for byte.
  strata::test::ScratchDir dir{"strata_file"};
  const std::string path = dir.file("example.strata");
  StrataContainer c;
  c.sections = {{"band0.positions", Bytes(9600, 0)}};
  write_strata_container(c, path);
  const Bytes file = slurp(path);
  ASSERT_EQ(file.size(), 9752u);
  EXPECT_EQ(le32(file, 12), 126u);
  EXPECT_EQ(std::string(file.begin() + 20, file.begin() + 146),
            R"({"format":"strata","version":1,"sections":[{"name":"band0.positions","offset":152,)"
            R"("size":9600,"crc32":1369079857}],"model":{}})");
  EXPECT_EQ(Bytes(file.begin(), file.begin() + 12),
            Bytes({0x89, 'S', 'T', 'R', 'A', 'T', 'A', 0x0A, 1, 0, 0, 0}));
}

TEST(StrataFile, HeaderLengthCrossingDigitBoundariesIsConsistent) {
  // The header's length feeds the offsets, whose digits feed the length: grow the model one byte
  // at a time across the point where the first offset reaches 1000 (4 digits) and check the
  // layout every time.
  strata::test::ScratchDir dir{"strata_file"};
  const std::string path = dir.file("sweep.strata");
  auto write_padded = [&](std::size_t pad) {
    StrataContainer c;
    c.model_json = OJson{{"p", std::string(pad, 'x')}}.dump();
    c.sections = {{"a", {1}}, {"b", {}}, {"c", {2, 3}}};
    write_strata_container(c, path);
    return slurp(path);
  };
  const std::size_t h0 = le32(write_padded(0), 12);  // the first offset is about 20 + h0 + pad
  ASSERT_LT(20 + h0, 1000u);
  std::set<std::size_t> first_offsets;
  for (std::size_t pad = 1000 - 20 - h0 - 24; pad < 1000 - 20 - h0 + 24; ++pad) {
    const Bytes file = write_padded(pad);
    const OJson table = check_layout(file);
    first_offsets.insert(table[0]["offset"].get<std::size_t>());
    const StrataContainer read = read_strata_container(path);
    ASSERT_EQ(read.sections.size(), 3u);
    EXPECT_EQ(read.sections[2].bytes, Bytes({2, 3}));
  }
  EXPECT_LT(*first_offsets.begin(), 1000u);
  EXPECT_GE(*first_offsets.rbegin(), 1000u);
}

TEST(StrataFile, HandBuiltFileFollowingFormatMdIsRead) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string path = dir.file("hand.strata");
  const std::vector<std::pair<std::string, Bytes>> sections = {
      {"x", {9, 8, 7}}, {"e", {}}, {"y", {1, 2, 3, 4, 5, 6, 7, 8, 9}}};
  const OJson model = {{"z", 1}, {"a", {1, 2}}};
  spit(path, hand_built_file(hand_built_header(sections, model), bytes_of(sections)));
  const StrataContainer read = read_strata_container(path);
  ASSERT_EQ(read.sections.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(read.sections[i].name, sections[i].first);
    EXPECT_EQ(read.sections[i].bytes, sections[i].second);
  }
  EXPECT_EQ(read.model_json, R"({"z":1,"a":[1,2]})");
}

TEST(StrataFile, PackIsLittleEndianAndUnpackChecksCounts) {
  EXPECT_EQ(pack_i32({0x01020304, -2}), Bytes({4, 3, 2, 1, 0xFE, 0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(pack_f64({1.0}), Bytes({0, 0, 0, 0, 0, 0, 0xF0, 0x3F}));
  EXPECT_TRUE(pack_f64({}).empty());

  const Section s{"sec", pack_f64({1.5, -2.25, 3.0})};
  EXPECT_EQ(unpack_f64(s, 3, "v"), std::vector<double>({1.5, -2.25, 3.0}));
  EXPECT_EQ(unpack_f64(s, -1, "v").size(), 3u);
  EXPECT_TRUE(unpack_i32(Section{"e", {}}, 0, "e").empty());
  auto expect_invalid = [](auto&& f, const std::string& needle) {
    try {
      f();
      ADD_FAILURE() << "expected InvalidInput containing " << needle;
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("band7 positions: ", 0), 0u) << msg;
      EXPECT_NE(msg.find(needle), std::string::npos) << msg;
    }
  };
  expect_invalid([&] { unpack_f64(s, 4, "band7 positions"); }, "expected 4");
  expect_invalid([&] { unpack_i32(s, 5, "band7 positions"); }, "expected 5");  // 24 bytes = 6 ints
  expect_invalid([&] { unpack_f64(Section{"odd", {1, 2, 3}}, -1, "band7 positions"); }, "whole number");
  expect_invalid([&] { unpack_i32(Section{"odd", {1, 2, 3, 4, 5}}, 1, "band7 positions"); }, "whole number");
  EXPECT_EQ(unpack_i32(Section{"i", {4, 3, 2, 1}}, 1, "i"), std::vector<std::int32_t>({0x01020304}));
}

TEST(StrataFile, FindAndRequire) {
  StrataContainer c;
  c.sections = {{"a", {1}}, {"b", {2}}};
  ASSERT_NE(c.find("b"), nullptr);
  EXPECT_EQ(c.find("b")->bytes, Bytes({2}));
  EXPECT_EQ(c.find("c"), nullptr);
  EXPECT_EQ(&c.require("a", "f.strata"), &c.sections[0]);
  try {
    c.require("c", "f.strata");
    ADD_FAILURE() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), "f.strata: missing section 'c'");
  }
}

TEST(StrataFile, WriteRejectsBadInputAndLeavesTheTargetUntouched) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string path = dir.file("keep.strata");
  std::mt19937_64 rng(7);
  write_strata_container(sample_container(rng), path);
  const Bytes before = slurp(path);

  auto expect_rejected = [&](const StrataContainer& c, const std::string& why) {
    EXPECT_THROW(write_strata_container(c, path), InvalidInput) << why;
    EXPECT_EQ(slurp(path), before) << why;
    EXPECT_EQ(dir.listing(), std::set<std::string>{"keep.strata"}) << why;
  };
  const std::vector<std::string> bad_names = {
      "", std::string(65, 'a'), "new\nline", "tab\t", "del\x7f", "caf\xc3\xa9", std::string("nul\0x", 5)};
  for (const std::string& name : bad_names) {
    StrataContainer c;
    c.sections = {{"ok", {1}}, {name, {2}}};
    expect_rejected(c, "name '" + name + "'");
  }
  {
    StrataContainer c;
    c.sections = {{"dup", {1}}, {"other", {}}, {"dup", {2}}};
    expect_rejected(c, "duplicate");
  }
  for (const std::string model : {"[]", "3", "\"s\"", "null", "", "{", "{\"a\":}", "{} {}", "not json"}) {
    StrataContainer c;
    c.model_json = model;
    expect_rejected(c, "model_json " + model);
  }
  {
    StrataContainer c;
    c.model_json = "{\"a\":" + std::string(300, '[') + std::string(300, ']') + "}";
    expect_rejected(c, "too deep");
    // The limit is the model's own depth, as FORMAT.md states it, for the writer and the reader
    // alike: 256 levels are written and read back (the reader counted the header around the
    // model too, and refused what the writer had written), 257 are refused.
    c.model_json = "{\"a\":" + std::string(255, '[') + std::string(255, ']') + "}";
    const std::string at_limit = dir.file("deep256.strata");
    write_strata_container(c, at_limit);
    EXPECT_EQ(read_strata_container(at_limit).model_json, c.model_json);
    std::remove(at_limit.c_str());
    c.model_json = "{\"a\":" + std::string(256, '[') + std::string(256, ']') + "}";
    expect_rejected(c, "257 levels");
  }
  {
    // A key twice, at any depth: JSON would keep one of the values silently.
    StrataContainer c;
    for (const std::string model : {"{\"a\":1,\"a\":1}", "{\"b\":[{\"x\":1,\"y\":2,\"x\":3}]}"}) {
      c.model_json = model;
      expect_rejected(c, "a key twice: " + model);
    }
    c.model_json = "{\"a\":{\"x\":1},\"b\":{\"x\":1}}";  // the same key in two objects is fine
    strata::test::ScratchDir other{"strata_file_twice"};
    write_strata_container(c, other.file("twice.strata"));
    EXPECT_EQ(read_strata_container(other.file("twice.strata")).model_json, c.model_json);
  }
  {
    StrataContainer c;
    c.model_json = many_keys(1025);
    expect_rejected(c, "1025 keys");
    c.model_json = many_keys(1024);  // the limit itself is accepted
    strata::test::ScratchDir other{"strata_file_keys"};
    write_strata_container(c, other.file("keys.strata"));
    EXPECT_EQ(read_strata_container(other.file("keys.strata")).model_json, c.model_json);
  }
  // A missing directory is an I/O error, and the target elsewhere is still untouched.
  EXPECT_THROW(write_strata_container(StrataContainer{}, dir.file("no/such/dir/x.strata")), IoError);
  EXPECT_EQ(slurp(path), before);

  // Longest and widest legal names are accepted.
  StrataContainer ok;
  ok.sections = {{std::string(64, '~'), {1}}, {" !\"#$%&'()*+,-./:;<=>?@[\\]^_`{|}", {}}};
  write_strata_container(ok, path);
  const StrataContainer read = read_strata_container(path);
  ASSERT_EQ(read.sections.size(), 2u);
  EXPECT_EQ(read.sections[1].name, ok.sections[1].name);
}

// ---------------------------------------------------------------------------------------------
// Corruption

TEST(StrataFile, TruncationIsReported) {
  strata::test::ScratchDir dir{"strata_file"};
  std::mt19937_64 rng(11);
  const std::string good = dir.file("good.strata"), cut = dir.file("cut.strata");
  write_strata_container(sample_container(rng), good);
  const Bytes file = slurp(good);
  const std::uint32_t h = le32(file, 12);

  std::set<std::size_t> lengths;
  for (std::size_t n = 0; n < 20; ++n) lengths.insert(n);  // every byte of the fixed prefix
  for (int i = 0; i < 40; ++i) lengths.insert(20 + static_cast<std::size_t>(rng() % h));  // inside the header
  lengths.insert(20 + h - 1);
  std::uint64_t pos = 20 + h;
  for (const auto& s : check_layout(file)) {  // every section boundary, before and after padding
    lengths.insert(pos);
    lengths.insert(s["offset"].get<std::size_t>());
    lengths.insert(s["offset"].get<std::size_t>() + s["size"].get<std::size_t>());
    if (s["size"] > 1) lengths.insert(s["offset"].get<std::size_t>() + 1);
    pos = s["offset"].get<std::uint64_t>() + s["size"].get<std::uint64_t>();
  }
  lengths.erase(file.size());
  ASSERT_GT(lengths.size(), 70u);
  for (const std::size_t n : lengths) {
    SCOPED_TRACE("truncated to " + std::to_string(n) + " of " + std::to_string(file.size()) + " bytes");
    spit(cut, Bytes(file.begin(), file.begin() + static_cast<std::ptrdiff_t>(n)));
    const std::string msg = expect_io_error(cut, "truncated");
    if (n > 20 + h) {
      EXPECT_NE(msg.find("section '"), std::string::npos) << msg;
    }
  }
}

TEST(StrataFile, EverySingleByteFlipIsDetected) {
  strata::test::ScratchDir dir{"strata_file"};
  std::mt19937_64 rng(12345);
  const std::string good = dir.file("good.strata"), bad = dir.file("bad.strata");
  write_strata_container(sample_container(rng, 40), good);
  const Bytes file = slurp(good);
  ASSERT_NO_THROW(read_strata_container(good));

  // Every position once, then random positions, each XORed with a random nonzero mask.
  std::vector<std::size_t> positions(file.size());
  for (std::size_t i = 0; i < file.size(); ++i) positions[i] = i;
  while (positions.size() < 4000) positions.push_back(rng() % file.size());
  int undetected = 0;
  std::set<std::string> kinds;
  spit(bad, file);
  for (const std::size_t at : positions) {
    // Patch one byte in place and restore it afterwards (cheaper than rewriting the file).
    poke(bad, at, static_cast<std::uint8_t>(file[at] ^ (1 + rng() % 255)));
    try {
      read_strata_container(bad);
      ++undetected;
      ADD_FAILURE() << "flip at byte " << at << " was not detected";
    } catch (const IoError& e) {
      const std::string msg = e.what();
      ASSERT_EQ(msg.rfind(bad + ": ", 0), 0u) << msg;
      kinds.insert(msg.substr(bad.size() + 2, 12));
    }
    poke(bad, at, file[at]);
  }
  EXPECT_EQ(undetected, 0);
  EXPECT_EQ(slurp(bad), file) << "every flip was undone";
  // The flips hit every kind of check: magic, version, lengths, header and section CRCs, padding.
  EXPECT_GE(kinds.size(), 5u);
}

TEST(StrataFile, ForeignFilesAreNotStrataFiles) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string p = dir.file("foreign");
  spit(p, {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 0, 0, 0, 0x0D,
           'I',  'H', 'D', 'R', 0,    0,    0,    1,    0, 0, 0, 1});
  expect_io_error(p, "bad magic");
  const std::string obj = "# a mesh\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  spit(p, Bytes(obj.begin(), obj.end()));
  expect_io_error(p, "bad magic");
  spit(p, {});
  expect_io_error(p, "truncated");
  spit(p, {'a', 'b', 'c'});
  expect_io_error(p, "bad magic");
  spit(p, {0x89, 'S', 'T'});
  expect_io_error(p, "truncated");
}

TEST(StrataFile, NewerAndZeroVersionsAreRefused) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string good = dir.file("good.strata"), patched = dir.file("patched.strata");
  std::mt19937_64 rng(3);
  write_strata_container(sample_container(rng), good);
  const Bytes file = slurp(good);
  for (const std::uint32_t v : {2u, 7u, 0xFFFFFFFFu}) {
    Bytes f = file;
    put_le32(f, 8, v);  // only the version field: the header still says 1
    spit(patched, f);
    const std::string msg = expect_io_error(patched, "newer");
    EXPECT_NE(msg.find("format version " + std::to_string(v)), std::string::npos) << msg;
    EXPECT_NE(msg.find("reads up to 1"), std::string::npos) << msg;
  }
  // Newer, even when truncated right after the version field.
  Bytes f(file.begin(), file.begin() + 12);
  put_le32(f, 8, 7);
  spit(patched, f);
  expect_io_error(patched, "newer");

  f = file;
  put_le32(f, 8, 0);
  spit(patched, f);
  expect_io_error(patched, "version 0");
}

TEST(StrataFile, TrailingBytesAreReported) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string good = dir.file("good.strata"), bad = dir.file("bad.strata");
  std::mt19937_64 rng(5);
  for (const bool with_sections : {true, false}) {
    write_strata_container(with_sections ? sample_container(rng) : StrataContainer{}, good);
    const Bytes file = slurp(good);
    for (const std::size_t extra : {1u, 7u, 8u, 100u}) {
      Bytes f = file;
      f.resize(file.size() + extra, 0);
      spit(bad, f);
      expect_io_error(bad, std::to_string(extra) + " trailing bytes");
    }
  }
}

TEST(StrataFile, DirectoriesAndMissingFilesAreIoErrors) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string sub = dir.file("a_directory");
  fs::create_directories(sub);
  expect_io_error(sub, "");
  expect_io_error(dir.file("missing.strata"), "");
}

TEST(StrataFile, MalformedHeadersAreReported) {
  strata::test::ScratchDir dir{"strata_file"};
  const std::string p = dir.file("malformed.strata");
  const Bytes s1 = {1, 2, 3}, s2 = {4, 5, 6, 7, 8, 9, 10, 11, 12};
  const std::vector<std::pair<std::string, Bytes>> two = {{"one", s1}, {"two", s2}};
  const OJson good = OJson::parse(hand_built_header(two));
  const std::uint64_t off1 = good["sections"][0]["offset"], off2 = good["sections"][1]["offset"];

  // Each case: a header (given a valid CRC-32) and the sections' bytes after it; the
  // section table keeps the canonical offsets unless the case changes them.
  auto check = [&](const std::string& header, const std::vector<Bytes>& sections, const std::string& needle) {
    SCOPED_TRACE(header.substr(0, 300));
    spit(p, hand_built_file(header, sections));
    expect_io_error(p, needle);
  };
  // The header \p edit makes of the good one. The offsets of the first \p canonical entries are
  // then recomputed for the edited header's length (as far as the entries allow), so that the
  // edit, not an offset shifted by it, is what the reader finds wrong.
  auto edited = [&](const std::function<void(OJson&)>& edit, std::size_t canonical = 2) {
    OJson j = good;
    edit(j);
    for (std::size_t assumed = 0; canonical > 0 && j.contains("sections") && j["sections"].is_array();) {
      std::uint64_t pos = 20 + assumed;
      for (std::size_t i = 0; i < std::min(canonical, j["sections"].size()); ++i) {
        OJson& e = j["sections"][i];
        if (!e.is_object() || !e.contains("offset") || !e["offset"].is_number_unsigned()) break;
        e["offset"] = align8(pos);
        if (!e.contains("size") || !e["size"].is_number_unsigned() ||
            e["size"].get<std::uint64_t>() > (1ull << 62))
          break;
        pos = align8(pos) + e["size"].get<std::uint64_t>();
      }
      if (j.dump().size() == assumed) break;
      assumed = j.dump().size();
    }
    return j.dump();
  };
  const std::vector<Bytes> both = {s1, s2};
  const std::string M = "malformed header";

  check("not json", both, M);
  // The parser's problem, without its exception class's name (a fuzzing pass, thirty-first session).
  check("not json", both, "malformed header: invalid JSON: parse error at line 1, column 2");
  check("", both, M);
  check("[1,2]", both, "not a JSON object");
  check(good.dump() + "x", both, M);
  for (const char* key : {"format", "version", "sections", "model"})
    check(edited([&](OJson& j) { j.erase(key); }), both, std::string("missing key '") + key);
  check(edited([](OJson& j) { j["extra"] = 1; }), both, "unknown key 'extra'");
  check(edited([](OJson& j) { j["format"] = "other"; }), both, "'format'");
  check(edited([](OJson& j) { j["format"] = 5; }), both, "'format'");
  check(edited([](OJson& j) { j["version"] = "1"; }), both, "'version'");
  check(edited([](OJson& j) { j["version"] = 1.0; }), both, "'version'");
  check(edited([](OJson& j) { j["version"] = 2; }), both, "'version' is 2");
  check(edited([](OJson& j) { j["sections"] = OJson::object(); }), both, "'sections' is not an array");
  for (const OJson& model : {OJson::array(), OJson(3), OJson("s"), OJson(nullptr)})
    check(edited([&](OJson& j) { j["model"] = model; }), both, "'model' is not a JSON object");
  {
    std::string deep = good.dump();
    deep.replace(deep.find("\"model\":{}"), 10,
                 "\"model\":{\"a\":" + std::string(400, '[') + std::string(400, ']') + "}");
    check(deep, both, "deeper");
    // A deep value followed by a key: the parse went on past the limit, and copying the value
    // as the object grew overflowed the stack (a crash at 100k levels).
    deep = good.dump();
    deep.replace(deep.find("\"model\":{}"), 10,
                 "\"model\":{\"a\":" + std::string(100000, '[') + std::string(100000, ']') + ",\"b\":1}");
    check(deep, both, "deeper");
  }
  {
    // 300k keys in one object took 49 s to read (a linear search per key); the parse stops at the
    // 1025th key. Not a timed test: a regression shows as a run of minutes.
    std::string many = good.dump();
    many.replace(many.find("\"model\":{}"), 10, "\"model\":" + many_keys(300000));
    check(many, both, "more than 1024 keys");
  }
  {
    // 100k empty objects in an array are within the limits and read back (nlohmann's callback
    // parser, which checked the limits before, took 33 s for 40k of them at -O0).
    std::string objects = "[{}";
    for (int k = 1; k < 100000; ++k) objects += ",{}";
    objects += "]";
    StrataContainer c;
    c.model_json = "{\"a\":" + objects + "}";
    strata::test::ScratchDir dir{"strata_file_objects"};
    write_strata_container(c, dir.file("o.strata"));
    EXPECT_EQ(read_strata_container(dir.file("o.strata")).model_json, c.model_json);
  }
  {
    // A key given twice, with the header's checksum valid: in the header itself, in a section
    // entry (the first value right, the second wrong), and inside the model.
    const std::string text = good.dump();
    auto twice = [&](const std::string& find, const std::string& replace) {
      std::string t = text;
      const std::size_t at = t.find(find);
      EXPECT_NE(at, std::string::npos) << find;
      return at == std::string::npos ? t : t.replace(at, find.size(), replace);
    };
    check(twice("{", "{\"version\":1,"), both, "the key \"version\" appears twice in one object");
    check(twice("\"name\":\"one\"", "\"name\":\"one\",\"name\":\"two\""), both,
          "the key \"name\" appears twice");
    check(twice("\"model\":{}", "\"model\":{\"a\":[{\"k\":1,\"k\":1}]}"), both,
          "malformed header: the key \"k\" appears twice");
  }
  // Section table entries. (Changing a header field can change the header's length and so the
  // canonical offsets: those cases expect whichever offset or length error follows.)
  check(edited([](OJson& j) { j["sections"][0] = 5; }), both, "entry 0 is not an object");
  for (const char* key : {"name", "offset", "size", "crc32"})
    check(edited([&](OJson& j) { j["sections"][1].erase(key); }), both, std::string("has no '") + key);
  check(edited([](OJson& j) { j["sections"][0]["extra"] = 0; }), both, "unknown keys");
  check(edited([](OJson& j) { j["sections"][0]["name"] = 1; }), both, "'name' is not a string");
  check(edited([](OJson& j) { j["sections"][0]["name"] = ""; }), both, "section name is empty");
  check(edited([](OJson& j) { j["sections"][0]["name"] = "a\nb"; }), both, "printable ASCII");
  check(edited([](OJson& j) { j["sections"][0]["name"] = std::string(65, 'x'); }), both, "at most 64");
  check(edited([](OJson& j) { j["sections"][1]["name"] = "one"; }), both, "duplicate section 'one'");
  check(edited([](OJson& j) { j["sections"][1]["size"] = -9; }), both,
        "'size' is not a non-negative integer");
  check(edited([](OJson& j) { j["sections"][1]["size"] = 9.0; }), both,
        "'size' is not a non-negative integer");
  check(edited([](OJson& j) { j["sections"][0]["offset"] = "40"; }), both, "'offset' is not");
  check(edited([](OJson& j) { j["sections"][0]["crc32"] = 0x100000000ull; }), both, "32 bits");
  check(edited([](OJson& j) { j["sections"][0]["crc32"] = true; }), both, "'crc32' is not");
  // Order and overlap: offsets that go backwards, overlap, leave a gap, or are misaligned.
  check(edited([&](OJson& j) { std::swap(j["sections"][0], j["sections"][1]); }, 0), {s2, s1}, "expected");
  check(edited([&](OJson& j) { j["sections"][1]["offset"] = off1; }, 1), both, "overlaps section 'one'");
  check(edited([&](OJson& j) { j["sections"][1]["offset"] = off1 + 1; }, 1), both, "overlaps section 'one'");
  check(edited([&](OJson& j) { j["sections"][0]["offset"] = 0; }, 0), both, "overlaps the header");
  check(edited([&](OJson& j) { j["sections"][1]["offset"] = off2 + 8; }, 1), both,
        "expected " + std::to_string(off2));
  check(edited([&](OJson& j) { j["sections"][1]["offset"] = off2 + 1; }, 1), both, "expected");
  // Sizes beyond the file never overflow or allocate.
  check(edited([](OJson& j) { j["sections"][1]["size"] = std::numeric_limits<std::uint64_t>::max(); }), both,
        "truncated: section 'two' ends at byte beyond");
  check(edited([](OJson& j) { j["sections"][0]["size"] = std::uint64_t{1} << 62; }), both,
        "truncated: section 'one' ends at byte 4611686018427388");  // 2^62 + its offset
  check(edited([](OJson& j) { j["sections"][1]["offset"] = std::numeric_limits<std::uint64_t>::max(); }, 1),
        both, "expected");

  // A wrong section CRC-32 names the section; nonzero padding is corruption.
  check(edited([](OJson& j) {
          j["sections"][1]["crc32"] = j["sections"][1]["crc32"].get<std::uint32_t>() ^ 1u;
        }),
        both, "section 'two' checksum mismatch (corrupted)");
  Bytes padded = hand_built_file(good.dump(), both);
  padded[off1 + s1.size()] = 0x20;
  spit(p, padded);
  expect_io_error(p, "nonzero padding");

  // And the unedited header is fine (so the failures above are the edits').
  spit(p, hand_built_file(good.dump(), both));
  EXPECT_EQ(read_strata_container(p).sections.size(), 2u);
}

}  // namespace
