#include "sim/run_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>

#include "sim/simulation.hpp"

namespace pp5 {

using namespace report;

Table bit_budget(const Program& program) {
  Table t;
  t.id = "bit-budget";
  Column field = text_column("field", "The field's name in the program");
  field.width = 16;
  Column bits = integer_column("bits", "bits", "The field's width");
  bits.heading = "bits";
  bits.width = 5;
  Column where = text_column("where",
                             "Where the field lives: its bits of pixel memory, or the "
                             "backing store's block");
  where.gap = 2;
  t.columns = {field, bits, where};
  for (const FieldDecl& f : program.fields) {
    t.add_row({f.name, f.width,
               f.spilled ? fmt::format("backing store, block {}", f.block)
                         : fmt::format("pixel memory [{}:{}]", f.lo + f.width - 1, f.lo)});
  }
  if (program.staging_bits) {
    t.add_row({"(staging)", program.staging_bits, "staging for spilled fields"});
  }
  t.add_row({"total", program.bits_used(),
             fmt::format("of {} bits ({:.0f}%)", program.memory_bits,
                         100.0 * program.bits_used() / program.memory_bits)});
  return t;
}

Table statistics_table(const Statistics& stats) {
  Table t;
  t.id = "statistics";
  t.columns = {code_column("statistic"), text_column("value"), text_column("unit"),
               text_column("description")};
  t.columns[1].align = Align::right;
  for (const StatisticInfo& i : stats.infos()) {
    const StatValue v = stats.value(i.name);
    Cell c;
    if (const auto* n = std::get_if<std::int64_t>(&v)) {
      c = Cell(*n);
    } else if (const auto* d = std::get_if<double>(&v)) {
      c = Cell::shown_as(Cell(*d), fmt::format("{:.6g}", *d));
    } else {
      c = Cell(std::get<std::string>(v));
    }
    t.add_row({i.name, c, i.unit, i.description});
  }
  return t;
}

namespace {

std::string run_report_json_value(const nlohmann::json& doc, const std::string& key) {
  const auto dot = key.find('.');
  const auto section = doc.find(key.substr(0, dot));
  if (section == doc.end()) return "";
  const auto value = section->find(key.substr(dot + 1));
  if (value == section->end()) return "";
  if (value->is_string()) return value->get<std::string>();
  if (value->is_number_float()) return fmt::format("{}", value->get<double>());
  return value->dump();
}

}  // namespace

Table configuration_table(const MachineConfig& config, std::vector<std::string>* differs) {
  const nlohmann::json doc = config.to_json();
  const nlohmann::json defaults = MachineConfig::defaults().to_json();
  Table t;
  t.id = "configuration";
  t.columns = {code_column("key"),  text_column("value"),       text_column("default"),
               text_column("unit"), text_column("calibration"), text_column("description")};
  for (const ParameterInfo& p : describe_parameters()) {
    std::string value = run_report_json_value(doc, p.key);
    std::string fallback = run_report_json_value(defaults, p.key);
    if (p.computed) {
      if (value.empty()) value = "computed";
      fallback = p.range;
    }
    if (fallback.empty()) fallback = p.default_value;
    if (value.empty()) value = fallback;
    const bool changed = !p.computed && value != fallback;
    if (changed && differs)
      differs->push_back(p.key + " = " + value + " (default " + fallback + ")");
    t.add_row({p.key, changed ? Cell("* " + value) : Cell(value), fallback, p.unit,
               std::string(calibration_name(p.calibration)), p.description});
  }
  return t;
}

std::vector<Track> timeline_tracks(const nlohmann::json& timeline, double* end_seconds) {
  const auto events = timeline.find("traceEvents");
  if (events == timeline.end()) {
    if (end_seconds) *end_seconds = 0;
    return {};
  }
  TimelineBusy busy(std::numeric_limits<std::size_t>::max());
  for (const auto& e : *events) busy.add(e);
  return busy.tracks(end_seconds);
}

TimelineBusy::TimelineBusy(std::size_t exact_limit) : exact_limit_(exact_limit) {}

void TimelineBusy::add(const nlohmann::json& e) {
  const std::string ph = e.value("ph", "");
  const Key track{e.value("pid", 0), e.value("tid", 0)};
  if (ph == "M" && e.value("name", "") == "thread_name") {
    names_[track] = e.at("args").value("name", "");
  } else if (ph == "X") {
    const double a = e.value("ts", 0.0) * 1e-6, b = a + e.value("dur", 0.0) * 1e-6;
    end_ = std::max(end_, b);
    if (track.first < 1 || track.first > 3) return;  // only GPs, ring channels, Renderers
    if (exact_) {
      busy_[track].push_back({a, b});
      if (++intervals_ > exact_limit_) to_bins();
    } else {
      grow_span(b);
      window_add(binned_[track], a, b);
    }
  } else if (ph == "i") {
    end_ = std::max(end_, e.value("ts", 0.0) * 1e-6);
  }
}

void TimelineBusy::to_bins() {
  exact_ = false;
  span_ = 0;
  grow_span(end_);
  for (auto& [track, slices] : busy_) {
    std::sort(slices.begin(), slices.end());
    Binned& b = binned_[track];
    b.bins.assign(kBins, 0.0);  // at once: memory stays flat from here on
    for (const auto& [a, e] : slices) window_add(b, a, e);
  }
  busy_.clear();
}

void TimelineBusy::grow_span(double end) {
  if (span_ <= 0) span_ = std::max(end, 1e-6);
  while (end > span_) {
    // Twice the span: bins 2i and 2i + 1 become bin i.
    for (auto& [track, b] : binned_) {
      if (b.bins.empty()) continue;
      for (std::size_t i = 0; i < kBins / 2; ++i) b.bins[i] = b.bins[2 * i] + b.bins[2 * i + 1];
      std::fill(b.bins.begin() + kBins / 2, b.bins.end(), 0.0);
    }
    span_ *= 2;
  }
}

void TimelineBusy::window_add(Binned& b, double start, double end) {
  // Merged with the intervals it overlaps or touches (slices of a track nest).
  auto it = b.window.upper_bound(start);
  if (it != b.window.begin() && std::prev(it)->second >= start) --it;
  while (it != b.window.end() && it->first <= end) {
    start = std::min(start, it->first);
    end = std::max(end, it->second);
    it = b.window.erase(it);
  }
  b.window.emplace(start, end);
  while (b.window.size() > kWindow) {
    bin_interval(b, b.window.begin()->first, b.window.begin()->second);
    b.window.erase(b.window.begin());
  }
}

void TimelineBusy::bin_interval(Binned& b, double start, double end) const {
  if (b.bins.empty()) b.bins.assign(kBins, 0.0);
  const double width = span_ / static_cast<double>(kBins);
  const double s = std::clamp(start / width, 0.0, static_cast<double>(kBins));
  const double e = std::clamp(end / width, 0.0, static_cast<double>(kBins));
  for (auto c = static_cast<std::size_t>(s); c < kBins && static_cast<double>(c) < e; ++c) {
    b.bins[c] += (std::min<double>(e, static_cast<double>(c) + 1) -
                  std::max<double>(s, static_cast<double>(c))) *
                 width;
  }
}

std::vector<Track> TimelineBusy::tracks(double* end_seconds) const {
  static const char* groups[] = {"", "GP", "ring channel", "Renderer", "frame buffer"};
  std::vector<Track> tracks;
  const double width = span_ / static_cast<double>(kBins);
  for (const auto& [track, name] : names_) {
    if (track.first < 1 || track.first > 3) continue;  // the frame buffer has instants only
    Track t;
    t.group = groups[track.first];
    t.name = name;
    if (exact_) {
      // Slices of a track nest: their union is the time the unit was busy.
      auto found = busy_.find(track);
      auto slices = found == busy_.end() ? std::vector<std::pair<double, double>>{} : found->second;
      std::sort(slices.begin(), slices.end());
      for (const auto& s : slices) {
        if (!t.intervals.empty() && s.first <= t.intervals.back().second) {
          t.intervals.back().second = std::max(t.intervals.back().second, s.second);
        } else {
          t.intervals.push_back(s);
        }
      }
    } else if (auto found = binned_.find(track); found != binned_.end()) {
      Binned b = found->second;
      while (!b.window.empty()) {  // the intervals still in the window
        bin_interval(b, b.window.begin()->first, b.window.begin()->second);
        b.window.erase(b.window.begin());
      }
      for (std::size_t c = 0; c < b.bins.size(); ++c) {
        const double busy = std::min(b.bins[c], width);  // a late nested slice counted twice
        if (busy > 0)
          t.intervals.push_back(
              {static_cast<double>(c) * width, static_cast<double>(c) * width + busy});
      }
    }
    tracks.push_back(std::move(t));
  }
  if (end_seconds) *end_seconds = end_;
  return tracks;
}

namespace {

Figure run_report_svg(std::string id, std::string title, std::string svg, std::string caption) {
  Figure f;
  f.id = std::move(id);
  f.title = std::move(title);
  f.mime = "image/svg+xml";
  f.bytes = std::move(svg);
  f.caption = std::move(caption);
  return f;
}

std::string percent(double ratio) { return fmt::format("{:.0f}%", 100 * ratio); }

}  // namespace

Report run_report(const RunReportInput& in) {
  const FrameResult& r = *in.result;
  const Statistics& s = r.stats;
  const MachineConfig& config = *in.config;
  Report rep;
  rep.title = "pp5sim: " + in.title;
  rep.subtitle = in.subtitle;

  // Headline figures and warnings first.
  Section& summary = rep.add_section("summary", "Summary");
  const int critical = static_cast<int>(s.integer("timing.critical_renderer"));
  const double f = r.frame_seconds > 0 ? r.frame_seconds : 1;
  Table head;
  head.id = "headline";
  head.columns = {text_column("figure"), real_column("value", "", -1), text_column("unit"),
                  text_column("what it is")};
  head.columns[1].heading = "value";
  auto figure = [&](const std::string& name, double value, int precision, const std::string& unit,
                    const std::string& what) {
    head.add_row({name, Cell::shown_as(Cell(value), format_real(value, precision)), unit, what});
  };
  figure("frame time", r.frame_seconds * 1e3, 3, "ms",
         "Simulated time from the frame's start to its last region in the frame buffer");
  figure("array cycles", static_cast<double>(s.integer("frame.array_cycles")), 0, "array cycles",
         "The frame time in Renderer array cycles");
  figure("triangles", static_cast<double>(s.integer("frame.triangles")), 0, "count",
         "Triangles in the display list");
  figure("throughput", r.triangles_per_second, 0, "triangles/s",
         "Triangles per second the real machine would reach");
  figure("frames per second", r.frame_seconds > 0 ? 1.0 / r.frame_seconds : 0.0, 1, "per second",
         "1 / frame time");
  figure("pipelined frame time", s.real("frame.pipelined_frame_seconds") * 1e3, 3, "ms",
         "With the GPs on the next frame while the Renderers finish this one");
  figure("GPs on the critical path", s.real("timing.gp_seconds") * 1e3, 3, "ms",
         fmt::format("{} of the frame: renderer {} waiting for GPs",
                     percent(s.real("timing.gp_seconds") / f), critical));
  figure("ring on the critical path", s.real("timing.ring_seconds") * 1e3, 3, "ms",
         fmt::format("{} of the frame: waiting for the ring",
                     percent(s.real("timing.ring_seconds") / f)));
  figure("Renderers on the critical path", s.real("timing.renderer_seconds") * 1e3, 3, "ms",
         fmt::format("{} of the frame: the Renderer's own work",
                     percent(s.real("timing.renderer_seconds") / f)));
  figure("host time", s.real("host.seconds"), 3, "host seconds",
         "Wall-clock time of the simulation on this computer");
  summary.blocks.push_back(head);
  summary.blocks.push_back(
      Note{Note::Level::info, fmt::format("Bottleneck: {} (the largest share of the critical path, "
                                          "which runs through renderer {}).",
                                          s.text("timing.bottleneck"), critical)});
  for (const std::string& w : in.warnings) summary.blocks.push_back(Note{Note::Level::warning, w});
  if (in.warnings.empty()) summary.blocks.push_back(Note{Note::Level::info, "No warnings."});

  Section& frame = rep.add_section("frame", "Frame");
  if (!in.frame_png.empty()) {
    Figure fig;
    fig.id = "frame-image";
    fig.mime = "image/png";
    fig.bytes = in.frame_png;
    fig.alt = "the rendered frame";
    fig.file = "frame.png";
    fig.caption =
        fmt::format("The frame as the frame buffer received it, {} x {} pixels (frame.png).",
                    config.screen.width, config.screen.height);
    frame.blocks.push_back(fig);
  } else {
    frame.blocks.push_back(
        Note{Note::Level::info, "No image: this run executed no pixels (fidelity.pixels=none)."});
  }

  // Regions: the heat map, and each Renderer's work.
  Section& regions = rep.add_section("regions", "Regions and Renderers");
  std::map<int, std::pair<int, std::uint64_t>> per_renderer;  // regions, busy cycles
  std::uint64_t peak = 0;
  for (const RegionLoad& l : r.regions) {
    per_renderer[l.renderer].first += 1;
    per_renderer[l.renderer].second += l.busy_cycles;
    peak = std::max(peak, l.busy_cycles);
  }
  int busiest = -1;
  std::uint64_t busiest_cycles = 0;
  for (const auto& [k, v] : per_renderer) {
    if (busiest < 0 || v.second > busiest_cycles) busiest = k, busiest_cycles = v.second;
  }
  if (!in.regions_png.empty()) {
    Figure fig;
    fig.id = "regions-image";
    fig.mime = "image/png";
    fig.bytes = in.regions_png;
    fig.alt = "regions heat map";
    fig.file = "regions.png";
    fig.caption = fmt::format(
        "regions.png: each region tinted by its Renderer's busy cycles on it (unit: array "
        "cycles), from 0 (dark blue) to the busiest region's {} (pale yellow). White outlines: "
        "the busiest Renderer ({}, {} array cycles over its regions). Cyan outlines, inside: the "
        "Renderer on the critical path ({}, whose last region reached the frame buffer last){}.",
        peak, busiest, busiest_cycles, critical,
        busiest == critical ? "; here they are the same Renderer" : "; they differ");
    regions.blocks.push_back(fig);
  }
  std::vector<Bar> bars;
  int highlight = -1;
  for (const auto& [k, v] : per_renderer) {
    if (k == critical) highlight = static_cast<int>(bars.size());
    std::string note = fmt::format("{} region{}", v.first, v.first == 1 ? "" : "s");
    if (k == busiest) note += ", busiest";
    if (k == critical) note += ", critical path";
    bars.push_back({fmt::format("renderer {}", k), static_cast<double>(v.second), note});
  }
  if (!bars.empty() && bars.size() <= 64) {
    regions.blocks.push_back(
        run_report_svg("renderer-busy", "Busy cycles per Renderer",
                       svg_bar_chart("Busy cycles per Renderer (the critical path's in orange)",
                                     bars, "array cycles", highlight),
                       "Each Renderer's busy cycles summed over the regions it rendered."));
  }

  // Bit budget.
  Section& budget = rep.add_section("bit-budget", "Bit budget");
  const Program& program = *in.program;
  std::vector<Part> parts;
  for (const FieldDecl& fd : program.fields) {
    if (!fd.spilled)
      parts.push_back({fd.name, static_cast<double>(fd.lo), static_cast<double>(fd.width)});
  }
  budget.blocks.push_back(run_report_svg(
      "bit-budget-map", "Pixel memory",
      svg_memory_map(fmt::format("Pixel memory of {}: {} of {} bits used",
                                 std::filesystem::path(program.name).filename().string(),
                                 program.bits_used(), program.memory_bits),
                     parts, program.memory_bits, "bits of pixel memory"),
      "Each resident field at its bits; fields on separate lanes share bits (scratch fields "
      "that are dead between procedures). Spilled fields live in the backing store (table)."));
  budget.blocks.push_back(bit_budget(program));

  // Utilisation and bottleneck.
  Section& util = rep.add_section("utilisation", "Utilisation and bottleneck");
  std::vector<Bar> ubars = {
      {"GPs, mean", 100 * s.real("timing.gp_utilisation_mean"), ""},
      {"GPs, max", 100 * s.real("timing.gp_utilisation_max"), ""},
      {"ring", 100 * s.real("timing.ring_utilisation"),
       fmt::format("of {:.2f} Gb/s", s.real("ring.bandwidth_bits_per_second") / 1e9)},
      {"ring, busiest channel", 100 * s.real("timing.ring_channel_utilisation_max"), ""},
      {"Renderers, mean", 100 * s.real("timing.renderer_utilisation_mean"), ""},
      {"Renderers, max", 100 * s.real("timing.renderer_utilisation_max"), ""},
  };
  util.blocks.push_back(run_report_svg(
      "utilisation-chart", "Utilisation",
      svg_bar_chart("Utilisation over the frame", ubars, "% of the frame time busy", -1, 100),
      "Busy time over the frame time, per kind of unit."));
  std::vector<Bar> path = {
      {"GPs", s.real("timing.gp_seconds") * 1e3, percent(s.real("timing.gp_seconds") / f)},
      {"ring", s.real("timing.ring_seconds") * 1e3, percent(s.real("timing.ring_seconds") / f)},
      {"Renderers", s.real("timing.renderer_seconds") * 1e3,
       percent(s.real("timing.renderer_seconds") / f)},
      {"unattributed", s.real("timing.unattributed_seconds") * 1e3,
       percent(s.real("timing.unattributed_seconds") / f)},
  };
  const std::string bottleneck = s.text("timing.bottleneck");
  const int bi = bottleneck == "GPs" ? 0 : bottleneck == "ring" ? 1 : 2;
  util.blocks.push_back(run_report_svg(
      "critical-path", "The frame time along the critical path",
      svg_bar_chart(fmt::format("Critical path (renderer {}): bottleneck {}", critical, bottleneck),
                    path, "simulated ms", bi),
      "What the critical-path Renderer spent the frame on: waiting for GPs, waiting for the "
      "ring, or its own work (docs/timing.md)."));

  Section& timeline = rep.add_section("timeline", "Timeline");
  if (in.timeline) {
    double end = 0;
    const std::vector<Track> tracks = timeline_tracks(*in.timeline, &end);
    timeline.blocks.push_back(run_report_svg(
        "timeline-chart", "Timeline", svg_timeline("Busy time of every unit", tracks, end),
        "Each GP, ring channel and Renderer over the frame; darker is busier. The same run's "
        "full timeline opens in a trace viewer with `pp5sim render --timeline FILE`."));
  } else {
    timeline.blocks.push_back(Note{Note::Level::info,
                                   "No timeline: the analytic timing model records no events "
                                   "(fidelity.timing=analytic)."});
  }

  Section& stats = rep.add_section("statistics", "Statistics");
  stats.blocks.push_back(
      Paragraph{"Every statistic of the run (stats.json), with its unit and "
                "description. Click a heading to sort; type to search."});
  stats.blocks.push_back(statistics_table(s));

  add_configuration_section(rep, config);
  return rep;
}

void add_configuration_section(report::Report& rep, const MachineConfig& config) {
  using namespace report;
  Section& conf = rep.add_section("configuration", "Configuration");
  std::vector<std::string> differs;
  Table ct = configuration_table(config, &differs);
  conf.blocks.push_back(
      Paragraph{differs.empty() ? std::string("Every key has its default value.")
                                : fmt::format("{} key{} differ from the defaults (marked *): {}.",
                                              differs.size(), differs.size() == 1 ? "" : "s",
                                              fmt::format("{}", fmt::join(differs, "; ")))});
  conf.blocks.push_back(ct);
}

}  // namespace pp5
