#pragma once
// A Report (sim/output/report.hpp) as one self-contained HTML page, and the charts a report
// draws as SVG.
//
// Contract:
//  - html(report) is a complete page that needs nothing outside itself: its style and script
//    are inline, its figures are data URIs, and it names no other address. Every table can be
//    sorted by a click on a heading; a table of more than 12 rows has a search box that
//    filters its rows. A heading's tooltip is its column's description and unit.
//  - Text from the report is escaped (&, <, >, "), so a scene or key name cannot inject markup.
//  - The charts are SVG documents (image/svg+xml) of a fixed size with their axes labelled,
//    units included; they read only their arguments.
#include <string>
#include <vector>

#include "sim/output/report.hpp"

namespace pp5::report {

std::string html(const Report& report);

std::string html_escape(const std::string& s);
std::string base64(const std::string& bytes);

// Horizontal bars, one per item (label, value), against a common scale with `unit`; each
// bar's `note` is printed after its value. `highlight`: the index of a bar drawn in another
// colour (-1 for none). The axis ends at `axis_end` (100 for percentages), or when it is 0 at
// a round number above the largest value.
struct Bar {
  std::string label;
  double value = 0;
  std::string note;
};
std::string svg_bar_chart(const std::string& title, const std::vector<Bar>& bars,
                          const std::string& unit, int highlight = -1, double axis_end = 0);

// A map of a memory `total` units long (the bits of pixel memory): each part a box from
// `start` to start + size, labelled; parts that overlap (fields sharing scratch bits) go on
// lanes of their own, and what no part covers is drawn as free.
struct Part {
  std::string label;
  double start = 0;
  double size = 0;
};
std::string svg_memory_map(const std::string& title, const std::vector<Part>& parts, double total,
                           const std::string& unit);

// A chart of busy time per track over the run: one row per track, the run cut into columns,
// each column shaded by the share of its time the track was busy.
struct Track {
  std::string group;                                 // "GP", "ring channel", "Renderer"
  std::string name;                                  // "gp0"
  std::vector<std::pair<double, double>> intervals;  // busy [start, end), in seconds
};
std::string svg_timeline(const std::string& title, const std::vector<Track>& tracks,
                         double end_seconds);

// An interactive plot of a data set's numeric columns: the reader chooses the x column, the
// y column and the column whose values make the lines (HTML with an inline script; no SVG
// file). `columns` are the data's columns, `rows` its values (as shown), `x_choices` the
// columns offered for x and for the series (the swept keys).
std::string html_plot(const Table& data, const std::vector<std::string>& x_choices,
                      const std::string& y_default);

}  // namespace pp5::report
