#include "strata/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "internal/read_file.h"
#include "strata/exceptions.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int err) {
  return std::strerror(err);
}

//! Closes a POSIX file descriptor on scope exit.
class FdGuard {
 public:
  explicit FdGuard(int fd) : fd_(fd) {}
  FdGuard(const FdGuard&) = delete;
  FdGuard& operator=(const FdGuard&) = delete;
  ~FdGuard() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }
  //! Closes now and reports the error, which matters after writing (NFS, quotas).
  int close_now() {
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc;
  }

 private:
  int fd_;
};

//! Creates a new, empty, uniquely named file next to \p target and returns its path.
std::string create_temp_file(const fs::path& target) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  // Keep the name well below NAME_MAX even for long target names.
  std::string stem = target.filename().string().substr(0, 180);
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  int last_err = 0;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string name = "." + stem + ".tmp." + std::to_string(::getpid()) + "." +
                             std::to_string(counter.fetch_add(1)) + "." + std::to_string(rd() % 1000000u);
    const std::string tmp = (dir / name).string();
    // O_EXCL guarantees we never clobber someone else's file; 0666 lets the umask decide as
    // for any newly created file.
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      FdGuard guard(fd);
      if (guard.close_now() != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        throw IoError(target.string() + ": cannot create temporary file " + tmp + ": " + errno_text(err));
      }
      return tmp;
    }
    last_err = errno;
    if (last_err != EEXIST) break;
  }
  throw IoError(target.string() + ": cannot create a temporary file in directory '" + dir.string() +
                "': " + errno_text(last_err));
}

//! Flushes the file's data to stable storage so the rename cannot expose an empty file after a crash.
void sync_file(const std::string& target, const std::string& tmp) {
  FdGuard fd(::open(tmp.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0)
    throw IoError(target + ": cannot reopen temporary file " + tmp + ": " + errno_text(errno));
  if (::fsync(fd.get()) != 0)
    throw IoError(target + ": cannot sync temporary file " + tmp + ": " + errno_text(errno));
  if (fd.close_now() != 0)
    throw IoError(target + ": cannot close temporary file " + tmp + ": " + errno_text(errno));
}

//! Best effort: makes the rename itself durable. Failure here does not undo a completed rename.
void sync_directory(const fs::path& target) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  FdGuard fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.get() >= 0) (void)::fsync(fd.get());
}

}  // namespace

void check_replaceable(const std::string& path) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0) return;                        // nothing there (or nothing we can see)
  if (S_ISLNK(st.st_mode) && ::stat(path.c_str(), &st) != 0) return;  // a link to nothing
  if (S_ISREG(st.st_mode)) return;
  const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                     : S_ISCHR(st.st_mode)  ? "a character device"
                     : S_ISBLK(st.st_mode)  ? "a block device"
                     : S_ISFIFO(st.st_mode) ? "a FIFO"
                     : S_ISSOCK(st.st_mode) ? "a socket"
                                            : "not a file";
  throw IoError(path + ": is not a regular file (" + kind + "); refusing to replace it");
}

void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& tmp_path)>& writer) {
  const fs::path target(path);
  if (path.empty() || !target.has_filename())
    throw IoError("'" + path + "': not a file path (empty or ends with a directory separator)");
  check_replaceable(path);

  // Replacing a file should not silently change its permissions (without set-id bits). They are
  // given to the temporary file after it is written and synced: given first, a read-only target
  // (0444) made the writer fail to open it, and a write-only one (0200) the sync.
  struct stat st;
  const bool keep_mode = ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
  const std::string tmp = create_temp_file(target);
  try {
    writer(tmp);
    sync_file(path, tmp);
    if (keep_mode) (void)::chmod(tmp.c_str(), st.st_mode & 0777);
    if (::rename(tmp.c_str(), path.c_str()) != 0)
      throw IoError(path + ": cannot replace it with temporary file " + tmp + ": " + errno_text(errno));
  } catch (...) {
    ::unlink(tmp.c_str());  // ignore failure: the original error is the one worth reporting
    throw;
  }
  sync_directory(target);
}

void write_text_file_atomically(const std::string& path, const std::string& contents) {
  write_file_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(path + ": cannot open temporary file " + tmp + " for writing");
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.close();
    if (!out) throw IoError(path + ": writing temporary file " + tmp + " failed (disk full?)");
  });
}

std::string read_file_bytes(const std::string& path) {
  return internal::read_whole_file(path);
}

}  // namespace strata
