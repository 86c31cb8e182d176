#include "sim/output/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace pp5::report {

std::string Column::shown_heading() const {
  if (!heading.empty()) return heading;
  return unit.empty() ? name : name + " (" + unit + ")";
}

std::string Column::csv_key() const { return key.empty() ? shown_heading() : key; }

bool Column::right_aligned() const {
  if (align != Align::automatic) return align == Align::right;
  return kind == Kind::integer || kind == Kind::real;
}

Column text_column(std::string name, std::string description) {
  Column c;
  c.name = std::move(name);
  c.description = std::move(description);
  return c;
}

Column code_column(std::string name, std::string description) {
  Column c = text_column(std::move(name), std::move(description));
  c.kind = Kind::code;
  return c;
}

Column integer_column(std::string name, std::string unit, std::string description) {
  Column c;
  c.name = std::move(name);
  c.unit = std::move(unit);
  c.description = std::move(description);
  c.kind = Kind::integer;
  return c;
}

Column real_column(std::string name, std::string unit, int precision, std::string description) {
  Column c = integer_column(std::move(name), std::move(unit), std::move(description));
  c.kind = Kind::real;
  c.precision = precision;
  return c;
}

Column headed(Column c, std::string heading, Align align) {
  c.heading = std::move(heading);
  c.align = align;
  return c;
}

Column left_aligned(Column c, std::string heading) {
  if (heading.empty()) heading = c.name;
  return headed(std::move(c), std::move(heading), Align::left);
}

Cell Cell::shown_as(Cell value, std::string text) {
  value.shown = std::move(text);
  return value;
}

std::optional<double> Cell::number() const {
  if (const auto* i = std::get_if<std::int64_t>(&value)) return static_cast<double>(*i);
  if (const auto* d = std::get_if<double>(&value)) return *d;
  return std::nullopt;
}

std::string format_real(double v, int precision) {
  if (precision < 0) return fmt::format("{:g}", v);
  return fmt::format("{:.{}f}", v, precision);
}

Table& Table::add_row(std::vector<Cell> cells) {
  if (cells.size() != columns.size()) {
    throw std::invalid_argument(fmt::format("table '{}': a row of {} cells, expected {} ({})",
                                            id.empty() ? title : id, cells.size(), columns.size(),
                                            columns.empty() ? "" : columns[0].shown_heading()));
  }
  rows.push_back(std::move(cells));
  return *this;
}

std::string Table::shown(std::size_t row, std::size_t column) const {
  const Cell& c = rows.at(row).at(column);
  if (!c.shown.empty()) return c.shown;
  if (const auto* i = std::get_if<std::int64_t>(&c.value)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&c.value)) {
    return format_real(*d, columns.at(column).precision);
  }
  if (const auto* s = std::get_if<std::string>(&c.value)) return *s;
  return "-";
}

Section& Report::add_section(std::string id, std::string title) {
  sections.push_back({std::move(id), std::move(title), {}});
  return sections.back();
}

namespace {

// A Markdown table cell must not hold a bare '|' or a line break.
std::string report_md_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += '\\';
    out += c == '\n' ? ' ' : c;
  }
  return out;
}

}  // namespace

std::string markdown(const Table& table) {
  std::string out = "|";
  for (const Column& c : table.columns) out += " " + report_md_escape(c.shown_heading()) + " |";
  out += "\n|";
  for (const Column& c : table.columns) out += c.right_aligned() ? "---:|" : "---|";
  out += "\n";
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    out += "|";
    for (std::size_t k = 0; k < table.columns.size(); ++k) {
      std::string cell = report_md_escape(table.shown(r, k));
      if (table.columns[k].kind == Kind::code && !table.rows[r][k].is_missing()) {
        cell = "`" + cell + "`";
      }
      out += " " + cell + " |";
    }
    out += "\n";
  }
  return out;
}

std::string markdown(const Report& report) {
  std::string out;
  if (!report.title.empty()) out += "# " + report.title + "\n\n";
  if (!report.subtitle.empty()) out += report.subtitle + "\n\n";
  for (const Section& s : report.sections) {
    if (!s.title.empty()) out += "## " + s.title + "\n\n";
    for (const Block& b : s.blocks) {
      if (const auto* p = std::get_if<Paragraph>(&b)) {
        out += p->text + "\n\n";
      } else if (const auto* t = std::get_if<Table>(&b)) {
        if (!t->title.empty()) out += "### " + t->title + "\n\n";
        out += markdown(*t) + "\n";
        if (!t->caption.empty()) out += t->caption + "\n\n";
      } else if (const auto* f = std::get_if<Figure>(&b)) {
        if (!f->file.empty())
          out += "![" + (f->alt.empty() ? f->title : f->alt) + "](" + f->file + ")\n\n";
        if (!f->caption.empty()) out += f->caption + "\n\n";
      } else if (const auto* n = std::get_if<Note>(&b)) {
        out += (n->level == Note::Level::warning ? "**Warning:** " : "") + n->text + "\n\n";
      } else if (const auto* pre = std::get_if<Preformatted>(&b)) {
        out += "```\n" + pre->text + (pre->text.empty() || pre->text.back() == '\n' ? "" : "\n") +
               "```\n\n";
      } else if (const auto* raw = std::get_if<RawHtml>(&b)) {
        if (!raw->markdown.empty()) out += raw->markdown + "\n\n";
      }
    }
  }
  while (out.size() > 1 && out[out.size() - 1] == '\n' && out[out.size() - 2] == '\n')
    out.pop_back();
  return out;
}

namespace {

std::string report_csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string csv(const Table& table) {
  std::string out;
  for (std::size_t k = 0; k < table.columns.size(); ++k) {
    out += (k ? "," : "") + report_csv_field(table.columns[k].csv_key());
  }
  out += "\n";
  for (const auto& row : table.rows) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (k) out += ",";
      const Cell& c = row[k];
      if (const auto* i = std::get_if<std::int64_t>(&c.value)) {
        out += std::to_string(*i);
      } else if (const auto* d = std::get_if<double>(&c.value)) {
        out += fmt::format("{:.9g}", *d);
      } else if (const auto* s = std::get_if<std::string>(&c.value)) {
        out += report_csv_field(*s);
      }
    }
    out += "\n";
  }
  return out;
}

std::string text(const Table& table) {
  const std::size_t n = table.columns.size();
  std::vector<std::size_t> widths(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Column& c = table.columns[k];
    if (c.width > 0) {
      widths[k] = static_cast<std::size_t>(c.width);
      continue;
    }
    widths[k] = c.shown_heading().size();
    for (std::size_t r = 0; r < table.rows.size(); ++r)
      widths[k] = std::max(widths[k], table.shown(r, k).size());
  }
  auto line = [&](const std::vector<std::string>& cells) {
    std::string out;
    for (std::size_t k = 0; k < n; ++k) {
      if (k) out += std::string(static_cast<std::size_t>(std::max(0, table.columns[k].gap)), ' ');
      const bool last = k + 1 == n;
      if (table.columns[k].right_aligned()) {
        out += fmt::format("{:>{}}", cells[k], widths[k]);
      } else {
        out += last ? cells[k] : fmt::format("{:<{}}", cells[k], widths[k]);
      }
    }
    return out + "\n";
  };
  std::vector<std::string> heading;
  for (const Column& c : table.columns) heading.push_back(c.shown_heading());
  std::string out = line(heading);
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    std::vector<std::string> cells;
    for (std::size_t k = 0; k < n; ++k) cells.push_back(table.shown(r, k));
    out += line(cells);
  }
  return out;
}

std::string text_records(const Table& table, std::size_t head) {
  std::string out;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    for (std::size_t k = 0; k < std::min(head, table.columns.size()); ++k) {
      out += (k ? " " : "") + table.shown(r, k);
    }
    out += "\n";
    for (std::size_t k = head; k < table.columns.size(); ++k) {
      out += "  " + table.columns[k].shown_heading() + ": " + table.shown(r, k) + "\n";
    }
  }
  return out;
}

}  // namespace pp5::report
