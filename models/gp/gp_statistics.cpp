// The statistics of the Graphics Processors and of set-up, registered from GpStats (see
// common/statistics.hpp for the registry's contract).
#include <iterator>
#include <string>

#include "common/statistics.hpp"
#include "models/gp/accurate_expressions.hpp"
#include "models/gp/graphics_processor.hpp"

namespace pp5 {

void GraphicsProcessor::register_statistics(Statistics& stats, double frame_seconds) const {
  register_gp_statistics(stats, index_, stats_, plan_.config().gp.clock_hz, frame_seconds);
}

void register_gp_statistics(Statistics& stats, int index, const GpStats& g, double clock_hz,
                            double frame_seconds) {
  namespace u = stat_unit;
  const std::string p = "gp." + std::to_string(index) + ".";
  stats.add_integer(p + "busy_clocks", u::gp_clocks,
                    "Clocks computing: geometry, and starting its ring messages",
                    [&g] { return stat_count(g.busy.count); });
  stats.add_integer(p + "geometry_clocks", u::gp_clocks,
                    "Of busy_clocks, those of transform, clip, light, set-up and binning (every "
                    "traversal of its share: one, or one per pass with gp.multipass=retraverse)",
                    [&g] { return stat_count(g.geometry.count); });
  stats.add_real(
      p + "utilisation", u::ratio, "busy_clocks as a fraction of the frame time",
      [&g, clock_hz, frame_seconds] { return g.busy.seconds(clock_hz) / frame_seconds; });
  stats.add_integer(p + "triangles_in", u::count, "Scene triangles this GP transformed",
                    [&g] { return stat_count(g.triangles_in); });
  stats.add_integer(p + "packets", u::count,
                    "Triangle packets it sent (one per region a triangle touches)",
                    [&g] { return stat_count(g.packets); });
  stats.add_integer(p + "messages", u::count,
                    "Ring messages it sent: its bin map and its bins' messages",
                    [&g] { return stat_count(g.messages); });
  const std::pair<const char*, const std::uint64_t OpCounts::*> ops[] = {
      {"fadd", &OpCounts::fadd},    {"fmul", &OpCounts::fmul},       {"load", &OpCounts::load},
      {"store", &OpCounts::store},  {"integer", &OpCounts::integer}, {"branch", &OpCounts::branch},
      {"chains", &OpCounts::chains}};
  const char* const meaning[] = {
      "i860 floating-point adder operations of the geometry (add, subtract, compare, convert)",
      "i860 floating-point multiplier operations of the geometry (reciprocal seeds included)",
      "i860 loads of the geometry",
      "i860 stores of the geometry",
      "i860 core integer and logic operations of the geometry",
      "i860 branches of the geometry",
      "Dependent floating-point chains of the geometry (each fills and drains a pipeline)"};
  for (std::size_t k = 0; k < std::size(ops); ++k) {
    const auto field = ops[k].second;
    stats.add_integer(p + "operations." + ops[k].first, u::count, meaning[k],
                      [&g, field] { return stat_count(g.ops.*field); });
  }
  if (g.sort.count > 0 || g.sort_messages > 0) {
    // Painter's depth sort, run before the geometry (a frame without one registers none).
    stats.add_integer(
        p + "depth_sort.clocks", u::gp_clocks,
        "Of busy_clocks, the depth sort's: prepare, merge, checks and inserted pieces",
        [&g] { return stat_count(g.sort.count); });
    stats.add_integer(p + "depth_sort.messages", u::count,
                      "Of messages, the depth sort's: runs, the order and records, GP to GP",
                      [&g] { return stat_count(g.sort_messages); });
    stats.add_integer(p + "depth_sort.ring_words", u::count, "Words of those messages",
                      [&g] { return stat_count(g.sort_words); });
    stats.add_real(p + "depth_sort.done_seconds", u::seconds,
                   "When its part of the depth sort ended, from the frame's start",
                   [&g] { return g.sort_done.to_seconds(); });
  }
  stats.add_real(p + "waiting_for_stage_seconds", u::seconds,
                 "Waiting for a Renderer to open the (region, pass) stage of its next bin",
                 [&g] { return g.waiting_stage.to_seconds(); });
  stats.add_real(p + "waiting_for_queue_seconds", u::seconds,
                 "Waiting for room in a Renderer's instruction queue",
                 [&g] { return g.waiting_queue.to_seconds(); });
  stats.add_real(p + "sending_seconds", u::seconds, "Waiting for its ring interface to send",
                 [&g] { return g.waiting_ring.to_seconds(); });
  stats.add_real(p + "geometry_done_seconds", u::seconds,
                 "When it finished the geometry of its share of the display list",
                 [&g] { return g.geometry_done.to_seconds(); });
  stats.add_real(p + "finished_seconds", u::seconds, "When it sent its last message",
                 [&g] { return g.finished.to_seconds(); });
}

void register_setup_statistics(Statistics& stats, std::vector<const GraphicsProcessor*> gps) {
  std::vector<const GpStats*> of;
  for (const GraphicsProcessor* gp : gps) of.push_back(&gp->stats());
  register_setup_statistics(stats, std::move(of));
}

void register_setup_statistics(Statistics& stats, std::vector<const GpStats*> gps) {
  namespace u = stat_unit;
  auto sum = [gps](auto get) {
    return [gps, get] {
      std::uint64_t total = 0;
      for (const GpStats* gp : gps) total += get(*gp);
      return stat_count(total);
    };
  };
  stats.add_integer("setup.packets", u::count,
                    "Triangle packets all GPs sent (one per triangle and region it touches)",
                    sum([](const GpStats& g) { return g.packets; }));
  stats.add_integer("setup.clipped_away", u::count,
                    "Triangles dropped wholly outside the view volume",
                    sum([](const GpStats& g) { return g.setup.clipped_away; }));
  stats.add_integer("setup.clip_splits", u::count, "Extra triangles made by clipping",
                    sum([](const GpStats& g) { return g.setup.clip_splits; }));
  stats.add_integer("setup.culled", u::count, "Back-facing triangles dropped (gp.cull_back_faces)",
                    sum([](const GpStats& g) { return g.setup.culled; }));
  stats.add_integer("setup.degenerate", u::count,
                    "Triangles dropped with zero area after snapping to the sub-pixel grid",
                    sum([](const GpStats& g) { return g.setup.degenerate; }));
  stats.add_integer("setup.no_pixel_centres", u::count,
                    "Triangles dropped that cover no pixel centre",
                    sum([](const GpStats& g) { return g.setup.no_pixels; }));
  // In SideKind order.
  static const char* const kSides[] = {
      "Triangle edges accurate scan conversion classified by the neighbour's plane (side0..2; "
      "0 for programs without them)",
      "Triangle edges accurate scan conversion classified by their own line: no neighbour",
      "Triangle edges classified by their own line: more than one neighbour (non-manifold)",
      "Triangle edges classified by the snapped edge: a piece of a clipped triangle, or its "
      "neighbour's triangle is clipped",
      "Triangle edges classified by their own line: the neighbour is edge-on to the eye",
      "Triangle edges classified by their own line: the planes are too nearly coplanar",
  };
  static_assert(std::size(kSides) == static_cast<std::size_t>(SideKind::count));
  for (int k = 0; k < static_cast<int>(SideKind::count); ++k) {
    stats.add_integer(
        std::string("setup.sides.") + side_kind_name(static_cast<SideKind>(k)), u::count, kSides[k],
        sum([k](const GpStats& g) { return g.setup.sides[static_cast<std::size_t>(k)]; }));
  }
  stats.add_integer("setup.coefficient_overflow", u::count,
                    "Triangles dropped because a coefficient did not fit "
                    "evaluator.coefficient_bits",
                    sum([](const GpStats& g) { return g.setup.overflow; }));
  stats.add_integer("setup.sphere_near_plane", u::count,
                    "Spheres dropped because they reach the near plane or hold the eye",
                    sum([](const GpStats& g) { return g.setup.sphere_near; }));
  stats.add_integer("setup.sphere_behind_eye", u::count, "Spheres dropped wholly behind the eye",
                    sum([](const GpStats& g) { return g.setup.sphere_behind; }));
  stats.add_integer("setup.sphere_far_plane", u::count,
                    "Spheres dropped because they reach the far plane",
                    sum([](const GpStats& g) { return g.setup.sphere_far; }));
}

}  // namespace pp5
