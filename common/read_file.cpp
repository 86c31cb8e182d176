#include "common/read_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace pp5 {

namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "is a directory";
  if (S_ISFIFO(mode)) return "is a FIFO";
  if (S_ISCHR(mode)) return "is a character device";
  if (S_ISBLK(mode)) return "is a block device";
  if (S_ISSOCK(mode)) return "is a socket";
  return "is not a regular file";
}

// Closes the descriptor on every path out.
struct Descriptor {
  int fd;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string read_regular_file(const std::string& path, std::uint64_t max_bytes,
                              const std::string& what, const std::string& bounded) {
  // O_NONBLOCK: opening a FIFO for reading must not wait for a writer; the fstat below then
  // refuses it.
  Descriptor file{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (file.fd < 0) {
    throw FileError(path + ": cannot open the file (" + std::strerror(errno) + "), expected " +
                    what);
  }
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) {
    throw FileError(path + ": cannot read (" + std::strerror(errno) + "), expected " + what);
  }
  if (!S_ISREG(st.st_mode)) {
    throw FileError(path + ": " + kind_of(st.st_mode) + ", expected " + what + " (a regular file)");
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > max_bytes) {
    throw FileError(path + ": " + std::to_string(size) + " bytes is larger than " +
                    (bounded.empty() ? what : bounded) + " can be (at most " +
                    std::to_string(max_bytes) + " bytes)");
  }
  std::string data(static_cast<std::size_t>(size), '\0');
  std::size_t got = 0;
  while (got < data.size()) {
    const ssize_t n = ::read(file.fd, data.data() + got, data.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      throw FileError(path + ": read error (" + std::strerror(errno) + ")");
    }
    if (n == 0) break;  // the file shrank while being read: take what is there
    got += static_cast<std::size_t>(n);
  }
  data.resize(got);
  return data;
}

}  // namespace pp5
