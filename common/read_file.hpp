#pragma once
// Reading an input file whole, safely: only a regular file (never a FIFO, a device such as
// /dev/zero, a socket or a directory, which would block forever or never end), and never
// more than a stated number of bytes, so that no input can hang a run or exhaust memory.
//
// Contract: returns the file's bytes, or throws FileError whose message starts with the path
// and says what was wrong and what was expected ("PATH: is a FIFO, expected a firmware
// program (a regular file)"). The check is made on the opened descriptor, so a file swapped
// for a FIFO between a look and the read is refused too.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace pp5 {

struct FileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// `what` names the expected content for messages, e.g. "a firmware program"; `bounded`, if
// given, says what max_bytes stands for ("a mesh within the limits (...)").
std::string read_regular_file(const std::string& path, std::uint64_t max_bytes,
                              const std::string& what, const std::string& bounded = "");

}  // namespace pp5
