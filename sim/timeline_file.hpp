#pragma once
// A run's timeline written out as the run records it (Session::stream_timeline), so that a
// run of many frames keeps none of it in memory: a staged output (StagedOutputs) that becomes
// the same document Session::run_frames would store, dumped compactly with a newline, byte for
// byte.
//
// Contract:
//  - The units' tracks and the slices go to the staged file as they come; the ring messages
//    (which the document holds after every slice) to a scratch file beside it, appended to
//    the file when the first event after them comes (the frame buffer's arrivals, or an event
//    the caller adds: pp5sim animate's track of frames) or at finish(). Each file's events
//    are buffered in kBuffer bytes (reserved at once) before each write.
//  - busy() has seen every event (TimelineBusy: a report's chart, in bounded memory).
//  - Errors (a full disk, a file-size limit) are OutputErrors naming the timeline's path.
#include <nlohmann/json.hpp>
#include <string>

#include "sim/output/output_set.hpp"
#include "sim/run_report.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

class TimelineFile : public TimelineStream {
 public:
  static constexpr std::size_t kBuffer = std::size_t{1} << 16;
  // `exact_limit`: TimelineBusy's.
  TimelineFile(StagedOutputs& outputs, const std::string& path,
               std::size_t exact_limit = std::size_t{1} << 17);
  void add(Part part, const nlohmann::json& event) override;
  // Completes the document; nothing may be added after it.
  void finish();
  const TimelineBusy& busy() const { return busy_; }

 private:
  void put(StagedFile& file, std::string& buffer, const std::string& bytes);
  void flush(StagedFile& file, std::string& buffer);
  void append_messages();
  std::string path_;
  StagedFile file_;
  std::string scratch_path_;
  StagedFile messages_;
  std::string file_buffer_, messages_buffer_;
  bool any_event_ = false;      // in the file
  bool messages_done_ = false;  // appended to the file
  bool any_message_ = false;
  bool finished_ = false;
  TimelineBusy busy_;
};

}  // namespace pp5
