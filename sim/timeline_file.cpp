#include "sim/timeline_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace pp5 {

TimelineFile::TimelineFile(StagedOutputs& outputs, const std::string& path, std::size_t exact_limit)
    : path_(path),
      file_(outputs, path),
      scratch_path_(outputs.scratch(file_.staged_path(), "ring-messages")),
      messages_(scratch_path_, path),
      busy_(exact_limit) {
  // The document as nlohmann::json dumps it: keys in order, no spaces.
  file_buffer_.reserve(2 * kBuffer);
  messages_buffer_.reserve(2 * kBuffer);
  file_buffer_ = "{\"displayTimeUnit\":\"ns\",\"traceEvents\":[";
}

void TimelineFile::put(StagedFile& file, std::string& buffer, const std::string& bytes) {
  buffer += bytes;
  if (buffer.size() >= kBuffer) flush(file, buffer);
}

void TimelineFile::flush(StagedFile& file, std::string& buffer) {
  file.write(buffer);
  buffer.clear();
}

void TimelineFile::add(Part part, const nlohmann::json& event) {
  if (finished_) throw std::logic_error("TimelineFile::add after finish");
  busy_.add(event);
  if (part == Part::messages) {
    if (messages_done_)
      throw std::logic_error("TimelineFile: a ring message after the events that follow them");
    put(messages_, messages_buffer_, "," + event.dump());
    any_message_ = true;
    return;
  }
  if (part == Part::units || part == Part::slices) {
    if (messages_done_)
      throw std::logic_error("TimelineFile: a slice after the events that follow the messages");
  } else {
    append_messages();
  }
  put(file_, file_buffer_, (any_event_ ? "," : "") + event.dump());
  any_event_ = true;
}

void TimelineFile::append_messages() {
  if (messages_done_) return;
  messages_done_ = true;
  if (!any_message_) return;
  flush(messages_, messages_buffer_);
  messages_.close();
  flush(file_, file_buffer_);
  const int fd = ::open(scratch_path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw OutputError(path_ + ": cannot read back the ring messages (" + std::strerror(errno) +
                      ")");
  std::string chunk(kBuffer, '\0');
  bool first = !any_event_;  // the first event of the document has no comma before it
  for (;;) {
    const ssize_t n = ::read(fd, chunk.data(), chunk.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      throw OutputError(path_ + ": cannot read back the ring messages (" + std::strerror(err) +
                        ")");
    }
    if (n == 0) break;
    const std::size_t skip = first ? 1 : 0;
    first = false;
    file_.write(chunk.data() + skip, static_cast<std::size_t>(n) - skip);
  }
  ::close(fd);
  ::unlink(scratch_path_.c_str());
  any_event_ = true;
}

void TimelineFile::finish() {
  if (finished_) return;
  append_messages();
  file_buffer_ += "]}\n";
  flush(file_, file_buffer_);
  file_.close();
  finished_ = true;
}

}  // namespace pp5
