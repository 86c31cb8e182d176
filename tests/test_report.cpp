// The report model (sim/output/report.hpp): one table, written as Markdown, CSV, text and HTML.
#include <catch2/catch.hpp>
#include <string>

#include "sim/output/report.hpp"
#include "sim/output/report_html.hpp"

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
