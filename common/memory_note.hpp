#pragma once
// What a run is working on, for the message when memory runs out (main's handler catches
// std::bad_alloc): the scene loader sets it as a scene is read, naming the input, its size
// and the bound a scene is held to, so that "out of memory" says which input and which limit
// would have stopped it. Reserved ahead, so that setting it needs no allocation for a note
// of up to kMemoryNoteBytes.
#include <string>
#include <string_view>

namespace pp5 {

inline constexpr std::size_t kMemoryNoteBytes = 512;

inline std::string& memory_note() {
  static std::string note = [] {
    std::string s;
    s.reserve(kMemoryNoteBytes);
    return s;
  }();
  return note;
}

inline void set_memory_note(std::string_view note) {
  memory_note().assign(note.substr(0, kMemoryNoteBytes));
}

}  // namespace pp5
