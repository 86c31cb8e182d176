#include "sim/analysis/field_render.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>

#include "common/parallel_for.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/pass_plan.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/renderer/renderer_board.hpp"

namespace pp5 {

FieldFrame render_field(const MachineConfig& config, const Scene& scene, const Program& program,
                        const std::string& field, int threads) {
  const FieldDecl* decl = program.find_field(field);
  if (decl == nullptr) {
    throw std::invalid_argument(
        fmt::format("{}: the program has no field '{}' to read back", program.name, field));
  }
  const GeometryEngine geometry(geometry_params(config), scene);
  check_pass_plan(program);
  FrameValues values = geometry.frame_values();
  set_pass_plan(program, scene, values);
  const RegionStream stream(program, values);

  // Every primitive of the display list through its kind, as the GPs do.
  std::vector<std::unique_ptr<PrimitiveWorker>> kind_workers;
  std::vector<ExpressionSet> needed;
  for (const PrimitiveKind* k : primitive_kinds()) {
    kind_workers.push_back(k->start(geometry));
    needed.push_back(program.procedure(k->procedure()).expressions);
  }
  std::vector<std::vector<std::shared_ptr<const Packet>>> bins(config.regions());
  FieldFrame out;
  SetupCounts counts;
  std::vector<int> regions;
  const DisplayList& list = geometry.display_list();
  for (int i = 0; i < list.size(); ++i) {
    const PrimitiveRef ref = list.at(i);
    const auto kind = static_cast<std::size_t>(ref.kind);
    PrimitiveWorker& worker = *kind_workers[kind];
    const int pieces = worker.transform(ref.index, counts);
    for (int piece = 0; piece < pieces; ++piece) {
      SetupResult r;
      if (!worker.setup(piece, needed[kind], r, counts)) continue;
      auto packet = std::make_shared<Packet>();
      packet->procedure = primitive_kinds()[kind]->procedure();
      packet->kind = ref.kind;
      packet->primitive = i;
      packet->group = primitive_kinds()[kind]->solid(scene, ref.index);
      packet->back = r.back;
      packet->values = r.values;
      regions.clear();
      worker.bin(r, regions);
      for (int region : regions) {
        bins[region].push_back(packet);
        ++out.packets;
      }
    }
  }

  const int w = config.screen.width;
  const int h = config.screen.height;
  const int rw = config.renderer.region_width;
  const int rh = config.renderer.region_height;
  const int across = (w + rw - 1) / rw;
  out.image.width = w;
  out.image.height = h;
  out.image.rgb.assign(static_cast<std::size_t>(w) * h * 3, 0);
  out.values.assign(static_cast<std::size_t>(w) * h, 0);
  const RendererBoardParams params = board_params(config);
  // A resident field is read in place; a spilled one is never the flag of these programs.
  if (decl->spilled) {
    throw std::invalid_argument(fmt::format(
        "{}: field '{}' lives in the backing store and cannot be read back", program.name, field));
  }
  const Field f{decl->lo, decl->width, decl->is_signed};
  // A board per host thread, made when the thread first needs it.
  struct Worker {
    std::optional<RendererBoard> board;
    std::vector<std::uint8_t> rgb;
  };
  std::vector<Worker> workers(
      static_cast<std::size_t>(parallel_workers(config.regions(), threads)));
  parallel_for(config.regions(), threads, [&](int region, int worker) {
    Worker& slot = workers[static_cast<std::size_t>(worker)];
    if (!slot.board) slot.board.emplace(params);
    RendererBoard& board = *slot.board;
    std::vector<std::uint8_t>& rgb = slot.rgb;
    const int x0 = (region % across) * rw;
    const int y0 = (region / across) * rh;
    board.begin_region(x0, y0);
    stream.for_each(bins[region], [&](const RegionStep& step) { board.run_step(step, region); });
    board.read_outputs(program, rgb);
    for (int y = 0; y < rh && y0 + y < h; ++y) {
      for (int x = 0; x < rw && x0 + x < w; ++x) {
        const int p = y * rw + x;
        const std::size_t q = static_cast<std::size_t>(y0 + y) * w + (x0 + x);
        for (int c = 0; c < 3; ++c) out.image.rgb[q * 3 + c] = rgb[p * 3 + c];
        out.values[q] = board.array().read(p, f);
      }
    }
  });
  return out;
}

}  // namespace pp5
