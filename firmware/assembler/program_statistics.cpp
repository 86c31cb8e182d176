#include "firmware/assembler/program_statistics.hpp"

#include "common/statistics.hpp"

namespace pp5 {

void register_program_statistics(Statistics& stats, const Program& program) {
  namespace u = stat_unit;
  stats.add_integer("pixel_memory.bits", u::bits,
                    "Pixel memory per pixel processor (renderer.memory_bits)",
                    [&program] { return std::int64_t{program.memory_bits}; });
  stats.add_integer("pixel_memory.used", u::bits, "Bits the program uses: resident plus staging",
                    [&program] { return std::int64_t{program.bits_used()}; });
  stats.add_integer("pixel_memory.resident", u::bits, "Bits of the fields kept in pixel memory",
                    [&program] { return std::int64_t{program.resident_bits}; });
  stats.add_integer("pixel_memory.staging", u::bits,
                    "Bits reserved for spilled fields while an instruction uses them",
                    [&program] { return std::int64_t{program.staging_bits}; });
}

}  // namespace pp5
