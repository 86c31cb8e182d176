// The statistics of the Renderers, registered from RendererStats and their regions' work (see
// common/statistics.hpp for the registry's contract).
#include <memory>
#include <string>

#include "common/statistics.hpp"
#include "models/renderer/renderer.hpp"

namespace pp5 {

void Renderer::register_statistics(Statistics& stats, double frame_seconds) const {
  register_renderer_statistics(stats, index_, stats_, plan_.config().renderer.clock_hz,
                               frame_seconds);
}

void register_renderer_statistics(Statistics& stats, int index, const RendererStats& st,
                                  double array_hz, double frame_seconds) {
  namespace u = stat_unit;
  const std::string p = "renderer." + std::to_string(index) + ".";
  stats.add_integer(p + "busy_cycles", u::array_cycles,
                    "Cycles executing micro-instructions, decoding packets and copying finished "
                    "colours to the backing store",
                    [&st] { return stat_count(st.busy.count); });
  stats.add_integer(p + "backing_store_stall_cycles", u::array_cycles,
                    "Cycles the array waited for the backing-store port",
                    [&st] { return stat_count(st.stall.count); });
  stats.add_real(
      p + "utilisation", u::ratio, "busy_cycles as a fraction of the frame time",
      [&st, array_hz, frame_seconds] { return st.busy.seconds(array_hz) / frame_seconds; });
  stats.add_real(p + "waiting_for_gps_seconds", u::seconds,
                 "Idle for a message while the GP that sent it was computing",
                 [&st] { return st.waiting_gp.to_seconds(); });
  stats.add_real(p + "waiting_for_ring_seconds", u::seconds,
                 "Idle for a message the GP was sending or the ring was carrying",
                 [&st] { return st.waiting_ring.to_seconds(); });
  stats.add_real(p + "waiting_for_other_renderers_seconds", u::seconds,
                 "Idle for a message while its GP waited for other Renderers' queues or stages",
                 [&st] { return st.waiting_renderers.to_seconds(); });
  stats.add_real(p + "blocked_shipping_seconds", u::seconds,
                 "Blocked shipping a finished region (renderer.overlap_shipping = 0)",
                 [&st] { return st.waiting_ship.to_seconds(); });
  stats.add_integer(p + "regions", u::count, "Screen regions it rendered",
                    [&st] { return stat_count(st.regions); });
  stats.add_integer(
      p + "packets", u::count,
      "Procedures it ran: the triangle packets of every pass, and clear, pass, light and "
      "shade",
      [&st] { return stat_count(st.packets); });
  stats.add_integer(p + "messages", u::count, "Bin messages it received from the GPs",
                    [&st] { return stat_count(st.messages); });
  stats.add_integer(p + "queue_peak_words", u::ring_words,
                    "Most words its instruction queue held at once",
                    [&st] { return stat_count(st.queue_peak_words); });
  stats.add_integer(p + "micro_instructions", u::count, "Micro-instructions issued to its array",
                    [&st] { return stat_count(st.instructions); });
  stats.add_real(p + "computed_seconds", u::seconds, "When its array finished its last region",
                 [&st] { return st.computed.to_seconds(); });
  stats.add_real(p + "finished_seconds", u::seconds,
                 "When its last region reached the frame buffer",
                 [&st] { return st.finished.to_seconds(); });
}

void register_renderer_totals(Statistics& stats, std::vector<const Renderer*> renderers,
                              int regions) {
  std::vector<const RendererStats*> st;
  std::vector<const std::vector<RegionWork>*> work;
  for (const Renderer* r : renderers) {
    st.push_back(&r->stats());
    work.push_back(&r->work());
  }
  register_renderer_totals(stats, std::move(st), std::move(work), regions);
}

void register_renderer_totals(Statistics& stats, std::vector<const RendererStats*> renderers,
                              std::vector<const std::vector<RegionWork>*> works, int regions) {
  namespace u = stat_unit;
  stats.add_integer("renderers_total.busy_cycles", u::array_cycles,
                    "busy_cycles summed over the Renderers", [renderers] {
                      std::uint64_t total = 0;
                      for (const RendererStats* r : renderers) total += r->busy.count;
                      return stat_count(total);
                    });
  stats.add_integer("renderers_total.micro_instructions", u::count,
                    "micro_instructions summed over the Renderers", [renderers] {
                      std::uint64_t total = 0;
                      for (const RendererStats* r : renderers) total += r->instructions;
                      return stat_count(total);
                    });
  // Counted once, on the first read, for every region at once.
  auto counts = std::make_shared<std::vector<std::uint64_t>>();
  auto count = [counts, works, regions](int region) {
    if (counts->empty()) {
      counts->assign(regions, 0);
      for (const std::vector<RegionWork>* work : works) {
        for (const RegionWork& w : *work) (*counts)[w.region] = w.triangles.size();
      }
    }
    return stat_count((*counts)[region]);
  };
  for (int k = 0; k < regions; ++k) {
    stats.add_integer("primitives_per_region." + std::to_string(k), u::count,
                      "Primitive packets of the region (row-major region index), one pass",
                      [count, k] { return count(k); });
  }
}

}  // namespace pp5
