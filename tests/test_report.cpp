// The report model (sim/output/report.hpp): one table, written as Markdown, CSV, text and HTML.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "sim/output/report.hpp"
#include "sim/output/report_html.hpp"
#include "sim/run_report.hpp"

using namespace pp5::report;

namespace {

Table sample_table() {
  Table t;
  t.id = "sample";
  t.columns = {text_column("scene"), integer_column("pixels", "", "Pixels compared"),
               real_column("frame", "ms", 3), code_column("expression")};
  t.add_row({"torus", 1024, 1.23456, "a | b"});
  t.add_row({"sphere, big", Cell::missing(), Cell::shown_as(Cell(2.0), "2.0 / 3"), "c"});
  return t;
}

}  // namespace

TEST_CASE("a table as Markdown: headings with units, numbers right-aligned, bars escaped",
          "[report]") {
  CHECK(markdown(sample_table()) ==
        "| scene | pixels | frame (ms) | expression |\n"
        "|---|---:|---:|---|\n"
        "| torus | 1024 | 1.235 | `a \\| b` |\n"
        "| sphere, big | - | 2.0 / 3 | `c` |\n");
}

TEST_CASE("a table as CSV: keys, full-precision values, quoted where needed", "[report]") {
  Table t = sample_table();
  t.columns[2].key = "frame_ms";
  CHECK(csv(t) ==
        "scene,pixels,frame_ms,expression\n"
        "torus,1024,1.23456,a | b\n"
        "\"sphere, big\",,2,c\n");
}

TEST_CASE("a table as text: the columns' least widths and gaps", "[report]") {
  Table t;
  t.columns = {text_column("field"), integer_column("bits"), text_column("where")};
  t.columns[0].width = 16;
  t.columns[1].width = 5;
  t.columns[2].gap = 2;
  t.add_row({"z", 24, "pixel memory [23:0]"});
  t.add_row({"a_very_long_field_name", 8, "x"});
  // As fmt's "{:<16} {:>5}  {}" lays it out (the summary's bit budget).
  CHECK(text(t) ==
        "field             bits  where\n"
        "z                   24  pixel memory [23:0]\n"
        "a_very_long_field_name     8  x\n");
  CHECK(text_records(t, 1) ==
        "z\n  bits: 24\n  where: pixel memory [23:0]\n"
        "a_very_long_field_name\n  bits: 8\n  where: x\n");
}

TEST_CASE("a row of the wrong size is refused, naming the table", "[report]") {
  Table t = sample_table();
  CHECK_THROWS_WITH(t.add_row({"x"}),
                    Catch::Contains("table 'sample': a row of 1 cells, expected 4"));
}

TEST_CASE("HTML: one page, escaped text, images inline, units in the headings", "[report]") {
  Report r;
  r.title = "a <b> & \"c\"";
  Section& s = r.add_section("one", "One");
  s.blocks.push_back(sample_table());
  Figure f;
  f.mime = "image/png";
  f.bytes = "abc";
  f.title = "pic";
  s.blocks.push_back(f);
  s.blocks.push_back(Note{Note::Level::warning, "careful <now>"});
  const std::string page = html(r);
  CHECK(page.find("<title>a &lt;b&gt; &amp; &quot;c&quot;</title>") != std::string::npos);
  CHECK(page.find("src=\"data:image/png;base64,YWJj\"") != std::string::npos);
  CHECK(page.find("frame <span class=\"unit\">(ms)</span>") != std::string::npos);
  CHECK(page.find("<b>Warning:</b> careful &lt;now&gt;") != std::string::npos);
  CHECK(page.find("data-n=\"1024\"") != std::string::npos);
  // Nothing outside the page: no src or href but data URIs and anchors.
  CHECK(page.find("src=\"http") == std::string::npos);
  CHECK(page.find("href=\"http") == std::string::npos);
  CHECK(page.find("<script src") == std::string::npos);
}

TEST_CASE("base64 of every length's tail", "[report]") {
  CHECK(base64("") == "");
  CHECK(base64("f") == "Zg==");
  CHECK(base64("fo") == "Zm8=");
  CHECK(base64("foo") == "Zm9v");
  CHECK(base64("foob") == "Zm9vYg==");
}

namespace {

// Busy seconds of each of `columns` columns over [0, end): what svg_timeline shades.
std::vector<double> report_test_columns(const pp5::report::Track& t, double end, int columns) {
  std::vector<double> busy(static_cast<std::size_t>(columns), 0.0);
  const double w = end / columns;
  for (const auto& [a, b] : t.intervals) {
    for (int c = static_cast<int>(a / w); c < columns && c * w < b; ++c) {
      busy[static_cast<std::size_t>(c)] +=
          std::max(0.0, std::min(b, (c + 1) * w) - std::max(a, c * w));
    }
  }
  return busy;
}

}  // namespace

TEST_CASE("the timeline chart in bounded memory: every column within one bin of the exact one",
          "[report]") {
  // Three units over a run of 10,000 "frames" of 1 ms, each frame a busy slice with two nested
  // ones and a gap: the exact chart (every interval kept) against the binned one
  // (TimelineBusy past its exact_limit), column by column as svg_timeline draws it. Mutation
  // tried: no window (each slice binned at once, nested slices counted twice): 1,128 of 1,128
  // column checks fail.
  pp5::TimelineBusy exact(std::numeric_limits<std::size_t>::max()), binned(1000);
  auto both = [&](const nlohmann::json& e) {
    exact.add(e);
    binned.add(e);
  };
  for (int tid = 0; tid < 3; ++tid) {
    both({{"ph", "M"},
          {"name", "thread_name"},
          {"pid", 3},
          {"tid", tid},
          {"args", {{"name", "renderer" + std::to_string(tid)}}}});
  }
  for (int f = 0; f < 10000; ++f) {
    for (int tid = 0; tid < 3; ++tid) {
      const double t0 = f * 1000.0 + 100 * tid + (f % 7) * 10;  // microseconds
      const double length = 300 + (f * 37 % 400);
      both({{"ph", "X"}, {"pid", 3}, {"tid", tid}, {"ts", t0 + 20}, {"dur", length / 3}});
      both({{"ph", "X"}, {"pid", 3}, {"tid", tid}, {"ts", t0}, {"dur", length}});
      both({{"ph", "X"}, {"pid", 3}, {"tid", tid}, {"ts", t0 + length / 2}, {"dur", length / 4}});
    }
  }
  CHECK(exact.exact());
  CHECK_FALSE(binned.exact());
  double end_exact = 0, end_binned = 0;
  const auto a = exact.tracks(&end_exact);
  const auto b = binned.tracks(&end_binned);
  CHECK(end_exact == end_binned);
  REQUIRE(a.size() == 3);
  REQUIRE(b.size() == 3);
  const int columns = 375;
  const double column = end_exact / columns;
  // A bin is at most twice the run over kBins: its time may land one column over at each edge.
  const double bin = 2 * end_exact / pp5::TimelineBusy::kBins;
  for (std::size_t k = 0; k < 3; ++k) {
    const auto ca = report_test_columns(a[k], end_exact, columns);
    const auto cb = report_test_columns(b[k], end_exact, columns);
    double total_a = 0, total_b = 0;
    for (int c = 0; c < columns; ++c) {
      INFO("track " << k << " column " << c);
      CHECK(std::abs(ca[c] - cb[c]) <= 2 * bin + 1e-12);
      CHECK(ca[c] <= column * (1 + 1e-9));
      total_a += ca[c];
      total_b += cb[c];
    }
    CHECK(total_b == Approx(total_a).epsilon(1e-9));
  }
}
