#include "sim/trace/inspect.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "firmware/isa/interface.hpp"

namespace pp5::trace {

std::map<Pixel, PixelState> replay(const Trace& t) {
  std::map<Pixel, PixelState> out;
  for (const Value& v : t.values) {
    PixelState& s = out[{v.rec.x, v.rec.y}];
    // The writer is the last instruction that wrote the field; a full-state record (start
    // of a window) counts only if it is the first sight of the field or shows a new value.
    const auto it = s.value.find(v.rec.field);
    const bool full = t.events[v.event].ins.flags & kFullState;
    if (!full || it == s.value.end() || it->second != v.rec.value) {
      s.last_writer[v.rec.field] = v.event;
    }
    s.value[v.rec.field] = v.rec.value;
  }
  return out;
}

Pixel choose_pixel(const Trace& t, const std::optional<Pixel>& requested) {
  if (requested) {
    if (std::find(t.pixels.begin(), t.pixels.end(), *requested) == t.pixels.end()) {
      throw TraceError(fmt::format("{}: pixel {},{} was not selected when the trace was recorded",
                                   t.path, requested->first, requested->second));
    }
    return *requested;
  }
  if (t.pixels.size() == 1) return t.pixels[0];
  throw TraceError(fmt::format("{}: the trace holds {} pixels; choose one with --pixel X,Y", t.path,
                               t.pixels.size()));
}

std::string describe_event(const Trace& t, const Event& e) {
  const InstructionText& it = t.text(e.ins);
  const std::string prim = packet_label(e.ins);
  return fmt::format("{} (proc {}, line {}: '{}'), micro-instruction #{} on renderer {}, cycle {}",
                     prim, kProcedureNames[e.ins.procedure], it.line, it.text, e.ins.seq,
                     e.ins.renderer, e.ins.cycle);
}

namespace {

std::string show(const Trace& t, int field, std::uint64_t raw) {
  const FieldInfo& f = t.fields[static_cast<std::size_t>(field)];
  if (f.is_signed) return fmt::format("{}", t.as_number(field, raw));
  if (f.width >= 12) return fmt::format("{} (0x{:x})", raw, raw);
  return fmt::format("{}", raw);
}

std::string firmware_name(const Trace& t) { return t.firmware_name; }

}  // namespace

std::string history_report(const Trace& t, Pixel px, const std::vector<std::string>& names,
                           bool every) {
  std::set<int> want;
  for (const std::string& n : names) {
    const int i = t.field_index(n);
    if (i < 0 || !t.fields[static_cast<std::size_t>(i)].traced) {
      throw TraceError(fmt::format("{}: field '{}' is not in the trace", t.path, n));
    }
    want.insert(i);
  }
  std::string out = fmt::format("pixel {},{}  firmware {}  scene {}\n", px.first, px.second,
                                firmware_name(t), t.scene_name);
  out += fmt::format("{:>8} {:>10} {:>8} {:>9} {:>5}  {:<28} {:>7}  {}\n", "instr#", "cycle",
                     "proc", "primitive", "line", "instruction", "enabled", "changes");
  std::size_t rows = 0;
  for (const Event& e : t.events) {
    std::string changes;
    for (std::size_t k = e.first_value; k < e.first_value + e.value_count; ++k) {
      const ValueRecord& v = t.values[k].rec;
      if (v.x != px.first || v.y != px.second) continue;
      if (!want.empty() && !want.count(v.field)) continue;
      changes += fmt::format("{}{}={}", changes.empty() ? "" : " ", t.fields[v.field].name,
                             show(t, v.field, v.value));
    }
    const bool mine =
        t.pixels.size() == 1 ||
        std::any_of(t.values.begin() + static_cast<long>(e.first_value),
                    t.values.begin() + static_cast<long>(e.first_value + e.value_count),
                    [&](const Value& v) { return v.rec.x == px.first && v.rec.y == px.second; });
    if (changes.empty() && !(every && mine)) continue;
    if (e.ins.flags & kFullState) changes = "(state at window start) " + changes;
    const InstructionText& it = t.text(e.ins);
    out += fmt::format("{:>8} {:>10} {:>8} {:>9} {:>5}  {:<28} {:>7}  {}\n", e.ins.seq, e.ins.cycle,
                       kProcedureNames[e.ins.procedure],
                       e.ins.primitive >= 0 ? std::to_string(e.ins.primitive) : std::string("-"),
                       it.line, it.text, e.ins.enabled, changes);
    ++rows;
  }
  out += fmt::format("{} rows\n", rows);
  return out;
}

std::string why_report(const Trace& t, Pixel px) {
  const auto states = replay(t);
  const auto it = states.find(px);
  if (it == states.end()) {
    return fmt::format("pixel {},{}: no instruction in the trace's window touched it\n", px.first,
                       px.second);
  }
  const PixelState& s = it->second;
  std::string out = fmt::format("pixel {},{}  firmware {}  scene {}\n", px.first, px.second,
                                firmware_name(t), t.scene_name);
  const std::vector<std::string>& outputs = t.outputs;
  std::string colour;
  bool complete = true;
  for (const auto& o : outputs) {
    const int f = t.field_index(o);
    if (f < 0 || !s.value.count(f)) {
      complete = false;
      continue;
    }
    colour += fmt::format("{}{}", colour.empty() ? "" : ", ", s.value.at(f) & 0xff);
  }
  if (complete) {
    out += fmt::format("colour (r, g, b) = ({}) from fields {}\n", colour,
                       fmt::format("{}", fmt::join(outputs.begin(), outputs.end(), " ")));
  }
  out += "\n";
  for (const auto& [field, value] : s.value) {
    out += fmt::format("{:<10} = {}\n", t.fields[static_cast<std::size_t>(field)].name,
                       show(t, field, value));
    const auto w = s.last_writer.find(field);
    if (w == s.last_writer.end()) {
      out += "             unchanged inside the trace's window\n";
      continue;
    }
    const Event& e = t.events[w->second];
    if (e.ins.flags & kFullState) {
      out += fmt::format("             set before the window began (first recorded at {})\n",
                         describe_event(t, e));
    } else {
      out += fmt::format("             last written by {}\n", describe_event(t, e));
    }
  }
  return out;
}

namespace {

// The shared fields' values after each packet of a pixel's region: (packet, primitive) ->
// field name -> value.
struct PacketState {
  std::uint32_t packet;
  std::int32_t primitive;
  std::uint8_t procedure;
  std::string label;  // packet_label
  std::map<std::string, std::uint64_t> values;
  std::map<std::string, std::size_t> writer;  // event of the last change in this packet
};

std::vector<PacketState> packet_states(const Trace& t, Pixel px,
                                       const std::set<std::string>& shared) {
  std::vector<PacketState> out;
  std::map<std::string, std::uint64_t> current;
  for (std::size_t k = 0; k < t.events.size(); ++k) {
    const Event& e = t.events[k];
    bool mine = false;
    std::map<std::string, std::size_t> writes;
    for (std::size_t i = e.first_value; i < e.first_value + e.value_count; ++i) {
      const ValueRecord& v = t.values[i].rec;
      if (v.x != px.first || v.y != px.second) continue;
      mine = true;
      const std::string& name = t.fields[v.field].name;
      if (!shared.count(name)) continue;
      if (!current.count(name) || current[name] != v.value) writes[name] = k;
      current[name] = v.value;
    }
    if (!mine) continue;
    if (out.empty() || out.back().packet != e.ins.packet) {
      out.push_back({e.ins.packet, e.ins.primitive, e.ins.procedure, packet_label(e.ins), {}, {}});
    }
    out.back().values = current;
    for (const auto& [n, w] : writes) out.back().writer[n] = w;
  }
  return out;
}

}  // namespace

std::string diff_report(const Trace& a, const Trace& b, std::optional<Pixel> pixel,
                        bool& diverged) {
  diverged = false;
  std::vector<Pixel> pixels;
  for (const Pixel& p : a.pixels) {
    if (std::find(b.pixels.begin(), b.pixels.end(), p) != b.pixels.end()) pixels.push_back(p);
  }
  if (pixel) {
    if (std::find(pixels.begin(), pixels.end(), *pixel) == pixels.end()) {
      throw TraceError(
          fmt::format("pixel {},{} is not in both traces", pixel->first, pixel->second));
    }
    pixels.assign(1, *pixel);
  }
  if (pixels.empty()) throw TraceError("the two traces have no selected pixel in common");
  std::set<std::string> shared, only_a, only_b;
  for (const FieldInfo& f : a.fields) {
    if (!f.traced) continue;
    const int j = b.field_index(f.name);
    if (j >= 0 && b.fields[static_cast<std::size_t>(j)].traced) {
      shared.insert(f.name);
    } else {
      only_a.insert(f.name);
    }
  }
  for (const FieldInfo& f : b.fields) {
    if (f.traced && !shared.count(f.name)) only_b.insert(f.name);
  }
  std::string out = fmt::format("A: {} (firmware {})\nB: {} (firmware {})\n", a.path,
                                firmware_name(a), b.path, firmware_name(b));
  out += fmt::format("fields compared: {}\n", fmt::join(shared, " "));
  if (!only_a.empty()) out += fmt::format("only in A: {}\n", fmt::join(only_a, " "));
  if (!only_b.empty()) out += fmt::format("only in B: {}\n", fmt::join(only_b, " "));
  out += "\n";
  for (const Pixel& px : pixels) {
    const auto sa = packet_states(a, px, shared);
    const auto sb = packet_states(b, px, shared);
    std::size_t i = 0, j = 0;
    bool found = false;
    while (i < sa.size() && j < sb.size()) {
      if (sa[i].packet != sb[j].packet) {  // a packet one trace's window left out
        (sa[i].packet < sb[j].packet ? i : j)++;
        continue;
      }
      if (sa[i].primitive != sb[j].primitive) {
        out += fmt::format(
            "pixel {},{}: packet {} is triangle {} in A but {} in B: the traces come from "
            "different scenes or configurations\n",
            px.first, px.second, sa[i].packet, sa[i].primitive, sb[j].primitive);
        diverged = found = true;
        break;
      }
      std::vector<std::string> differ;
      for (const std::string& n : shared) {
        const auto va = sa[i].values.find(n), vb = sb[j].values.find(n);
        if (va == sa[i].values.end() || vb == sb[j].values.end()) continue;
        if (va->second != vb->second) differ.push_back(n);
      }
      if (!differ.empty()) {
        const std::string& what = sa[i].label;
        out += fmt::format("pixel {},{}: first divergence after packet {} ({}):\n", px.first,
                           px.second, sa[i].packet, what);
        for (const std::string& n : differ) {
          const int fa = a.field_index(n), fb = b.field_index(n);
          out += fmt::format("  {:<8} A = {:<20} B = {}\n", n, show(a, fa, sa[i].values.at(n)),
                             show(b, fb, sb[j].values.at(n)));
          if (sa[i].writer.count(n)) {
            out += fmt::format("           A: written by {}\n",
                               describe_event(a, a.events[sa[i].writer.at(n)]));
          }
          if (sb[j].writer.count(n)) {
            out += fmt::format("           B: written by {}\n",
                               describe_event(b, b.events[sb[j].writer.at(n)]));
          }
        }
        diverged = found = true;
        break;
      }
      ++i;
      ++j;
    }
    if (!found) {
      out += fmt::format("pixel {},{}: no difference in the compared fields over {} packets\n",
                         px.first, px.second, std::min(sa.size(), sb.size()));
    }
  }
  return out;
}

std::string bitmap_report(const Trace& t) {
  std::vector<std::uint64_t> touched(t.fields.size(), 0);
  std::map<std::pair<Pixel, int>, std::uint64_t> last;
  for (const Value& v : t.values) {
    const auto key = std::make_pair(Pixel{v.rec.x, v.rec.y}, static_cast<int>(v.rec.field));
    const auto it = last.find(key);
    if (it != last.end()) touched[v.rec.field] |= it->second ^ v.rec.value;
    last[key] = v.rec.value;
  }
  const int memory_bits = t.memory_bits;
  std::string out = fmt::format(
      "pixel memory of {} bits, firmware {}: '#' a bit that changed during the trace, '.' one "
      "that did not, '-' a field not traced\n\n",
      memory_bits, firmware_name(t));
  out += fmt::format("{:<10} {:>9} {:>5} {:>6}  {}\n", "field", "bits", "width", "sign",
                     "touched (msb .. lsb)");
  std::vector<char> map(static_cast<std::size_t>(memory_bits), '.');
  int used = 0;
  for (std::size_t i = 0; i < t.fields.size(); ++i) {
    const FieldInfo& f = t.fields[i];
    if (f.lo < 0) {
      out += fmt::format("{:<10} {:>9} {:>5} {:>6}  spilled to the backing store\n", f.name, "-",
                         f.width, f.is_signed ? "signed" : "");
      continue;
    }
    std::string bits;
    int n = 0;
    for (int b = f.width - 1; b >= 0; --b) {
      const bool on = (touched[i] >> b) & 1;
      bits += !f.traced ? '-' : on ? '#' : '.';
      n += on;
    }
    used += f.width;
    const char letter = static_cast<char>(i < 26 ? 'a' + i : 'A' + (i - 26) % 26);
    for (int b = 0; b < f.width && f.lo + b < memory_bits; ++b) {
      map[static_cast<std::size_t>(f.lo + b)] =
          f.traced && ((touched[i] >> b) & 1) ? static_cast<char>(std::toupper(letter)) : letter;
    }
    out += fmt::format("{:<10} {:>9} {:>5} {:>6}  {}  {}\n", f.name,
                       fmt::format("[{}:{}]", f.lo + f.width - 1, f.lo), f.width,
                       f.is_signed ? "signed" : "", bits,
                       f.traced ? fmt::format("{}/{} touched", n, f.width) : "");
  }
  out += fmt::format(
      "\nmemory map, bit {} at the left, bit 0 at the right; a field's letter in upper case where "
      "a bit was touched, '.' unused ({} of {} bits in fields):\n",
      memory_bits - 1, used, memory_bits);
  for (int row = (memory_bits - 1) / 64; row >= 0; --row) {
    std::string line;
    const int hi = std::min(memory_bits, (row + 1) * 64) - 1;
    for (int b = hi; b >= row * 64; --b) line += map[static_cast<std::size_t>(b)];
    out += fmt::format("{:>4}..{:<4} {}\n", hi, row * 64, line);
  }
  for (std::size_t i = 0; i < t.fields.size() && i < 52; ++i) {
    if (t.fields[i].lo < 0) continue;
    out += fmt::format("{}{}={}", i % 8 ? "  " : (i ? "\n" : ""),
                       static_cast<char>(i < 26 ? 'a' + i : 'A' + (i - 26) % 26), t.fields[i].name);
  }
  out += "\n";
  return out;
}

namespace {

std::string vcd_id(std::size_t n) {
  std::string s;
  do {
    s += static_cast<char>(33 + n % 94);
    n /= 94;
  } while (n);
  return s;
}

std::string binary(std::uint64_t v, int width) {
  std::string s = "b";
  for (int b = width - 1; b >= 0; --b) s += ((v >> b) & 1) ? '1' : '0';
  return s;
}

std::string ascii_bits(const std::string& text, int chars) {
  std::string s = "b";
  for (int c = 0; c < chars; ++c) {
    const auto ch = static_cast<unsigned char>(c < static_cast<int>(text.size()) ? text[c] : ' ');
    for (int b = 7; b >= 0; --b) s += ((ch >> b) & 1) ? '1' : '0';
  }
  return s;
}

}  // namespace

std::string vcd(const Trace& t) {
  const double clock_hz = t.clock_hz;  // checked when read: 1e6 .. 1e9
  const auto ps_per_cycle = static_cast<std::uint64_t>(std::llround(1e12 / clock_hz));
  int text_chars = 8;
  for (const auto& p : t.procedures) {
    for (const auto& i : p) text_chars = std::max(text_chars, static_cast<int>(i.text.size()));
  }
  std::set<int> renderers;
  for (const Event& e : t.events) renderers.insert(e.ins.renderer);
  std::vector<int> traced;
  for (std::size_t i = 0; i < t.fields.size(); ++i) {
    if (t.fields[i].traced) traced.push_back(static_cast<int>(i));
  }

  std::string out = "$comment pp5sim per-pixel trace: " + t.path + " $end\n";
  out += "$version pp5sim $end\n$timescale 1ps $end\n$scope module pp5 $end\n";
  std::size_t next = 0;
  struct Stream {
    std::string opcode, text, line, primitive, procedure, enabled, number;
  };
  std::map<int, Stream> streams;
  for (int r : renderers) {
    Stream s{vcd_id(next),     vcd_id(next + 1), vcd_id(next + 2), vcd_id(next + 3),
             vcd_id(next + 4), vcd_id(next + 5), vcd_id(next + 6)};
    next += 7;
    out += fmt::format("$scope module renderer{} $end\n", r);
    out += fmt::format("$var wire 8 {} opcode [7:0] $end\n", s.opcode);
    out += fmt::format("$var wire {} {} instruction [{}:0] $end\n", 8 * text_chars, s.text,
                       8 * text_chars - 1);
    out += fmt::format("$var wire 16 {} line [15:0] $end\n", s.line);
    out += fmt::format("$var wire 32 {} primitive [31:0] $end\n", s.primitive);
    out += fmt::format("$var wire 3 {} procedure [2:0] $end\n", s.procedure);
    out += fmt::format("$var wire 32 {} enabled_pixels [31:0] $end\n", s.enabled);
    out += fmt::format("$var wire 64 {} instruction_number [63:0] $end\n", s.number);
    out += "$upscope $end\n";
    streams[r] = s;
  }
  std::map<std::pair<Pixel, int>, std::string> ids;
  for (const Pixel& p : t.pixels) {
    out += fmt::format("$scope module pixel_{}_{} $end\n", p.first, p.second);
    for (int f : traced) {
      const FieldInfo& fi = t.fields[static_cast<std::size_t>(f)];
      const std::string id = vcd_id(next++);
      ids[{p, f}] = id;
      out += fmt::format("$var wire {} {} {} [{}:0] $end\n", fi.width, id, fi.name, fi.width - 1);
    }
    out += "$upscope $end\n";
  }
  out += "$upscope $end\n$enddefinitions $end\n";

  // Changes, ordered by time; the stable sort keeps each Renderer's order.
  struct Change {
    std::uint64_t time;
    std::string text;
  };
  std::vector<Change> changes;
  for (const Event& e : t.events) {
    const Stream& s = streams[e.ins.renderer];
    const std::uint64_t at = e.ins.cycle * ps_per_cycle;
    const InstructionText& it = t.text(e.ins);
    const int opcode = it.opcode;
    std::string c;
    c += binary(static_cast<std::uint64_t>(opcode), 8) + " " + s.opcode + "\n";
    c += ascii_bits(it.text, text_chars) + " " + s.text + "\n";
    c += binary(static_cast<std::uint64_t>(it.line), 16) + " " + s.line + "\n";
    c += binary(static_cast<std::uint32_t>(e.ins.primitive), 32) + " " + s.primitive + "\n";
    c += binary(e.ins.procedure, 3) + " " + s.procedure + "\n";
    c += binary(e.ins.enabled, 32) + " " + s.enabled + "\n";
    c += binary(e.ins.seq, 64) + " " + s.number + "\n";
    changes.push_back({at, c});
    std::string v;
    for (std::size_t k = e.first_value; k < e.first_value + e.value_count; ++k) {
      const ValueRecord& r = t.values[k].rec;
      v += binary(r.value, t.fields[r.field].width) + " " +
           ids[{Pixel{r.x, r.y}, static_cast<int>(r.field)}] + "\n";
    }
    if (!v.empty()) changes.push_back({(e.ins.cycle + e.ins.cost) * ps_per_cycle, v});
  }
  std::stable_sort(changes.begin(), changes.end(),
                   [](const Change& a, const Change& b) { return a.time < b.time; });
  out += "#0\n$dumpvars\n";
  for (const auto& [r, s] : streams) {
    for (const std::string* id :
         {&s.opcode, &s.text, &s.line, &s.primitive, &s.procedure, &s.enabled, &s.number}) {
      out += "bx " + *id + "\n";
    }
  }
  for (const auto& [key, id] : ids) out += "bx " + id + "\n";
  out += "$end\n";
  std::uint64_t now = 0;
  for (const Change& c : changes) {
    if (c.time != now) {
      out += fmt::format("#{}\n", c.time);
      now = c.time;
    }
    out += c.text;
  }
  return out;
}

}  // namespace pp5::trace
