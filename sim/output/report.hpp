#pragma once
// A report as data, and the one writer that renders it.
//
// An analysis or a run builds a Report: sections of blocks, each a paragraph, a table whose
// columns carry a kind, a unit and a description, a figure (an encoded image), a note (a
// warning or a remark) or preformatted text. It never formats Markdown, CSV or HTML itself:
//  - markdown(table) / markdown(report): GitHub Markdown ("| a | b |", numbers right-aligned);
//  - csv(table): RFC 4180, one heading row of the columns' keys, values at full precision;
//  - text(table): fixed-width columns for a terminal; text_records(table): one record a row
//    (for long cells);
//  - html(report) (sim/output/report_html.hpp): one self-contained page.
//
// Contract:
//  - A cell holds a typed value (integer, real, text, or missing) and, optionally, how it is
//    shown ("1.5 / 3", a range): Markdown, text and HTML show `shown` when it is set, else the
//    value formatted by its column (a real with the column's precision); CSV writes the value.
//    A missing value is shown as "-" and written as an empty CSV field.
//  - A column's heading is `heading` when set, else its name with the unit in brackets.
//  - Table::add_row throws std::invalid_argument when a row's cells do not match the columns.
//  - The writers read only their arguments: the same report gives the same bytes.
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace pp5::report {

enum class Kind { text, integer, real, code };  // code: shown in `backticks` in Markdown
enum class Align { automatic, left, right };    // automatic: numbers right, the rest left

struct Column {
  std::string name;
  std::string unit;  // "" for none
  std::string description;
  Kind kind = Kind::text;
  int precision = -1;  // a real's digits after the point; -1: the shortest exact form ({:g})
  Align align = Align::automatic;
  std::string heading;  // Markdown, text and HTML heading; "": name (unit)
  std::string key;      // CSV heading; "": the heading
  int width = 0;        // text(): the least width (as fmt's {:<N}); 0: the widest cell's
  int gap = 1;          // text(): spaces before the column (after the previous one)

  std::string shown_heading() const;
  std::string csv_key() const;
  bool right_aligned() const;
};

// Constructors that read as a column list: text_column("scene"), number("frame", "ms", 3).
Column text_column(std::string name, std::string description = {});
Column code_column(std::string name, std::string description = {});
Column integer_column(std::string name, std::string unit = {}, std::string description = {});
Column real_column(std::string name, std::string unit, int precision, std::string description = {});
// `c` with its heading text fixed and its alignment chosen: a table converted from
// hand-written Markdown keeps its text (the unit still in Column::unit, for HTML and CSV).
Column headed(Column c, std::string heading, Align align = Align::automatic);
// `c` left-aligned under `heading` (its name when empty), as the hand-written tables were.
Column left_aligned(Column c, std::string heading = {});

struct Cell {
  std::variant<std::monostate, std::int64_t, double, std::string> value;
  std::string shown;  // "": formatted from the value

  Cell() = default;
  Cell(std::int64_t v) : value(v) {}
  Cell(int v) : value(static_cast<std::int64_t>(v)) {}
  Cell(std::uint64_t v) : value(static_cast<std::int64_t>(v)) {}
  Cell(long long v) : value(static_cast<std::int64_t>(v)) {}
  Cell(double v) : value(v) {}
  Cell(std::string v) : value(std::move(v)) {}
  Cell(const char* v) : value(std::string(v)) {}
  // A value shown as `text` (the CSV keeps the value).
  static Cell shown_as(Cell value, std::string text);
  static Cell missing() { return Cell(); }
  bool is_missing() const { return std::holds_alternative<std::monostate>(value); }
  std::optional<double> number() const;  // integer or real, else none
};

struct Table {
  std::string id;       // a file name stem and an HTML anchor ("bit-budget")
  std::string title;    // a heading above the table in a report ("" for none)
  std::string caption;  // a paragraph below it ("" for none)
  std::vector<Column> columns;
  std::vector<std::vector<Cell>> rows;
  // Whether a report's files include it as ID.csv (sim/app add_report_outputs); false for a
  // table shown only, whose values another table of the same report holds in full.
  bool csv_file = true;

  Table& add_row(std::vector<Cell> cells);
  // Cell (row, column) as Markdown, text and HTML show it (without Markdown's escapes).
  std::string shown(std::size_t row, std::size_t column) const;
};

// An encoded image: PNG or SVG bytes, embedded in HTML as a data URI; in Markdown a link to
// `file` (written beside the Markdown by whoever writes it) when set.
struct Figure {
  std::string id;
  std::string title;
  std::string caption;
  std::string mime;  // "image/png" or "image/svg+xml"
  std::string bytes;
  std::string alt;
  std::string file;  // "" for none
};

struct Note {
  enum class Level { info, warning };
  Level level = Level::info;
  std::string text;
};

struct Paragraph {
  std::string text;
};
struct Preformatted {
  std::string text;
};
// HTML made by a writer of this folder (a chart, the statistics' search box); Markdown and
// text leave it out. Never built from unescaped input.
struct RawHtml {
  std::string html;
  std::string markdown;  // what Markdown shows instead ("" for nothing)
};

using Block = std::variant<Paragraph, Table, Figure, Note, Preformatted, RawHtml>;

struct Section {
  std::string id;
  std::string title;
  std::vector<Block> blocks;
};

struct Report {
  std::string title;
  std::string subtitle;
  std::vector<Section> sections;
  Section& add_section(std::string id, std::string title);
};

// A real as a column shows it.
std::string format_real(double v, int precision);

std::string markdown(const Table& table);
std::string markdown(const Report& report);
std::string csv(const Table& table);
std::string text(const Table& table);
// Each row as a line of its first `head` cells (joined by a space), then one indented line
// "  heading: value" for each other column.
std::string text_records(const Table& table, std::size_t head);

}  // namespace pp5::report
