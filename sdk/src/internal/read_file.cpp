#include "internal/read_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <system_error>

#include "strata/exceptions.h"

namespace strata::internal {
namespace {
namespace fs = std::filesystem;
[[noreturn]] void fail_io(const std::string& name, const std::string& what) {
  throw IoError(name + ": " + what);
}
}  // namespace

std::string read_whole_file(const std::string& path) {
  // Only regular files: a FIFO or a device like /dev/zero could block or never end.
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) fail_io(path, "cannot read: not a regular file");
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Closer> f(std::fopen(path.c_str(), "rb"));
  if (!f) fail_io(path, std::string("cannot open: ") + std::strerror(errno));
  std::string data;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f.get())) > 0) data.append(buf, n);
  if (std::ferror(f.get())) fail_io(path, std::string("read error: ") + std::strerror(errno));
  return data;
}

}  // namespace strata::internal
