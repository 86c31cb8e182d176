#include "sim/animation_report.hpp"

#include <fmt/format.h>

#include "sim/output/report_html.hpp"
#include "sim/run_report.hpp"

namespace pp5 {

using namespace report;

namespace {

Figure animation_figure(std::string id, std::string title, std::string mime, std::string bytes,
                        std::string caption, std::string file = {}) {
  Figure f;
  f.id = std::move(id);
  f.title = std::move(title);
  f.mime = std::move(mime);
  f.bytes = std::move(bytes);
  f.caption = std::move(caption);
  f.alt = f.title;
  f.file = std::move(file);
  return f;
}

}  // namespace

Report animation_report(const AnimationReportInput& in) {
  Report rep;
  rep.title = "pp5sim: " + in.title;
  rep.subtitle = in.subtitle;
  const RunSummary& s = in.summary;

  Section& summary = rep.add_section("summary", "Summary");
  Table head;
  head.id = "run";
  head.columns = {text_column("figure"), text_column("value"), text_column("what it is")};
  head.add_row({"frames", fmt::format("{}", s.frames), "Frames simulated, one after the other"});
  head.add_row({"mean frame time", fmt::format("{:.3f} ms", s.mean_frame_seconds() * 1e3),
                "Simulated frame times, averaged"});
  head.add_row({"shortest .. longest",
                fmt::format("{:.3f} .. {:.3f} ms", s.shortest_frame_seconds * 1e3,
                            s.longest_frame_seconds * 1e3),
                "The fastest and slowest frame"});
  head.add_row({"simulated time", fmt::format("{:.3f} ms", s.simulated_seconds * 1e3),
                "The frames' simulated times, summed"});
  head.add_row({"animation rate", fmt::format("{:g} frames/s", in.fps),
                "The rate the GIF plays at (not the machine's)"});
  head.add_row({"host seconds per simulated second", fmt::format("{:.3g}", s.host_over_simulated()),
                "Below 1 the simulator keeps up with the machine"});
  summary.blocks.push_back(head);

  Section& anim = rep.add_section("animation", "Animation");
  if (!in.gif.empty()) {
    anim.blocks.push_back(animation_figure(
        "animation-gif", "The animation", "image/gif", in.gif,
        fmt::format(
            "animation.gif: the {} frames at {:g} frames/s, looping (a 252-colour palette).",
            in.frames.size(), in.fps),
        "animation.gif"));
  } else {
    anim.blocks.push_back(
        Note{Note::Level::info, "No images: this run executed no pixels (fidelity.pixels=none)."});
  }

  Section& frames = rep.add_section("frames", "Frames");
  Table t;
  t.id = "frames";
  t.columns = {integer_column("frame"),
               real_column("start", "ms", 3, "The frame's start in the run's simulated time"),
               real_column("frame time", "ms", 3, "Simulated frame time"),
               real_column("throughput", "triangles/s", 0, "Triangles per simulated frame time"),
               text_column("bottleneck", "timing.bottleneck"),
               real_column("GP utilisation max", "", 3),
               real_column("Renderer utilisation max", "", 3),
               real_column("ring utilisation", "", 3),
               integer_column("Renderer busy", "array cycles", "Summed over the regions")};
  std::vector<Bar> times, busy;
  for (std::size_t k = 0; k < in.frames.size(); ++k) {
    const AnimationFrameRow& f = in.frames[k];
    t.add_row({static_cast<std::int64_t>(k), f.start_seconds * 1e3, f.frame_seconds * 1e3,
               f.triangles_per_second, f.bottleneck, f.gp_utilisation_max,
               f.renderer_utilisation_max, f.ring_utilisation,
               static_cast<std::int64_t>(f.renderer_busy_cycles)});
    times.push_back({fmt::format("frame {}", k), f.frame_seconds * 1e3, f.bottleneck});
    busy.push_back({fmt::format("frame {}", k), static_cast<double>(f.renderer_busy_cycles), ""});
  }
  frames.blocks.push_back(t);
  frames.blocks.push_back(animation_figure(
      "frame-times", "Frame time per frame", "image/svg+xml",
      svg_bar_chart("Simulated frame time", times, "ms"),
      "Each frame's simulated time, with its bottleneck (frames.csv's frame_ms)."));
  frames.blocks.push_back(animation_figure(
      "renderer-busy", "Renderer work per frame", "image/svg+xml",
      svg_bar_chart("Renderer busy cycles, summed over the regions", busy, "array cycles"),
      "What the Renderers' arrays did each frame (frames.csv's renderer_busy_cycles)."));

  Section& images = rep.add_section("frame-images", "Frame images");
  for (std::size_t k = 0; k < in.frame_pngs.size(); ++k) {
    images.blocks.push_back(animation_figure(
        fmt::format("frame-{}", k), fmt::format("Frame {}", k), "image/png", in.frame_pngs[k],
        fmt::format("frame-{:04d}.png: {:.3f} ms simulated, {}-bound.", k,
                    in.frames[k].frame_seconds * 1e3, in.frames[k].bottleneck),
        fmt::format("frame-{:04d}.png", k)));
  }
  if (in.frame_pngs.empty()) {
    images.blocks.push_back(Note{Note::Level::info, "No images: no pixels executed."});
  }

  Section& regions = rep.add_section("regions", "Regions over the frames");
  if (!in.regions_png.empty()) {
    regions.blocks.push_back(animation_figure(
        "regions-image", "Regions heat map, summed", "image/png", in.regions_png,
        "regions.png: each region tinted by its Renderer busy cycles summed over every frame "
        "(unit: array cycles), over the last frame.",
        "regions.png"));
  }

  Section& timeline = rep.add_section("timeline", "Timeline");
  if (in.timeline) {
    double end = 0;
    const std::vector<Track> tracks = in.timeline->tracks(&end);
    timeline.blocks.push_back(animation_figure(
        "timeline-chart", "Timeline", "image/svg+xml",
        svg_timeline("Busy time of every unit over all frames", tracks, end),
        "Each GP, ring channel and Renderer over every frame; darker is busier. timeline.json "
        "opens in ui.perfetto.dev, with a track marking each frame."));
  } else {
    timeline.blocks.push_back(
        Note{Note::Level::info, "No timeline (fidelity.timing=analytic, or --no-timeline)."});
  }

  add_configuration_section(rep, *in.config);
  return rep;
}

}  // namespace pp5
