#pragma once
// The pixel-memory statistics of an assembled program (stats.json's pixel_memory.*).
#include "firmware/assembler/assembler.hpp"

namespace pp5 {

class Statistics;

// Registers pixel_memory.*; reads `program` when read, so it must outlive the reads (or the
// registry's freeze()).
void register_program_statistics(Statistics& stats, const Program& program);

}  // namespace pp5
