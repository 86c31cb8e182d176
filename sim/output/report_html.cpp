#include "sim/output/report_html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace pp5::report {

std::string html_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += digits[(v >> 18) & 63];
    out += digits[(v >> 12) & 63];
    out += digits[(v >> 6) & 63];
    out += digits[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += digits[(v >> 18) & 63];
    out += digits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

namespace {

constexpr const char* kReportStyle = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#1d1d1f;background:#fafafa}
header{background:#20304a;color:#fff;padding:14px 28px}
header h1{margin:0;font-size:22px}header p{margin:4px 0 0;color:#c9d3e3}
nav{padding:8px 28px;background:#e8ecf2;font-size:14px}nav a{margin-right:14px;color:#20304a}
main{padding:8px 28px 40px;max-width:1400px}
section{background:#fff;border:1px solid #dde2ea;border-radius:6px;padding:6px 18px 14px;margin:16px 0}
h2{font-size:18px;border-bottom:1px solid #e3e7ee;padding-bottom:4px}h3{font-size:15px}
table{border-collapse:collapse;font-size:13px;margin:6px 0}
th,td{border:1px solid #d6dbe3;padding:3px 7px;vertical-align:top}
th{background:#eef1f6;cursor:pointer;user-select:none;text-align:left}
th.num,td.num{text-align:right}td.num{font-variant-numeric:tabular-nums}
th .unit{font-weight:normal;color:#5a6475}
tr.differs td{background:#fff5d6}
code{font-size:12px}
figure{margin:8px 0}figure img{max-width:min(100%,1000px);border:1px solid #ccd;image-rendering:pixelated}
figcaption{font-size:13px;color:#444;margin-top:4px;max-width:900px}
.note{padding:6px 10px;border-left:4px solid #7a8ca8;background:#f2f5f9;margin:6px 0}
.warning{border-left-color:#d9822b;background:#fff3e6}
div.wide{overflow-x:auto}div.scroll{max-height:640px;overflow:auto;border:1px solid #e3e7ee}
input.search{margin:6px 0;padding:4px 6px;width:320px}
pre{background:#f4f4f4;padding:8px;overflow:auto;font-size:12px}
.plot select{margin-right:12px}
)";

// Sorting by a heading's click, the search boxes, and the plots (html_plot).
constexpr const char* kReportScript = R"(
(function(){
  function cellValue(td){
    var n=td.getAttribute('data-n');
    return n===null?td.textContent:parseFloat(n);
  }
  document.querySelectorAll('table.report').forEach(function(table){
    var heads=table.querySelectorAll('thead th');
    heads.forEach(function(th,col){
      th.addEventListener('click',function(){
        var body=table.tBodies[0];
        var rows=Array.prototype.slice.call(body.rows);
        var dir=th.getAttribute('data-dir')==='asc'?-1:1;
        heads.forEach(function(h){h.removeAttribute('data-dir');});
        th.setAttribute('data-dir',dir===1?'asc':'desc');
        rows.sort(function(a,b){
          var x=cellValue(a.cells[col]),y=cellValue(b.cells[col]);
          if(typeof x==='number'&&typeof y==='number'){
            if(isNaN(x))return 1;if(isNaN(y))return -1;return (x-y)*dir;
          }
          return String(x).localeCompare(String(y))*dir;
        });
        rows.forEach(function(r){body.appendChild(r);});
      });
    });
  });
  document.querySelectorAll('input.search').forEach(function(input){
    var table=document.getElementById(input.getAttribute('data-table'));
    input.addEventListener('input',function(){
      var q=input.value.toLowerCase();
      Array.prototype.forEach.call(table.tBodies[0].rows,function(r){
        r.style.display=r.textContent.toLowerCase().indexOf(q)>=0?'':'none';
      });
    });
  });
  var SVG='http://www.w3.org/2000/svg';
  function el(name,attrs,text){
    var e=document.createElementNS(SVG,name);
    for(var k in attrs)e.setAttribute(k,attrs[k]);
    if(text!==undefined)e.textContent=text;
    return e;
  }
  function fmt(v){
    var a=Math.abs(v);
    if(a!==0&&(a>=1e6||a<1e-3))return v.toExponential(2);
    return String(Math.round(v*1000)/1000);
  }
  document.querySelectorAll('div.plot').forEach(function(div){
    var data=JSON.parse(div.querySelector('script').textContent);
    var sx=div.querySelector('select.x'),sy=div.querySelector('select.y'),ss=div.querySelector('select.series');
    var sl=div.querySelector('input.logy');
    var holder=div.querySelector('div.chart');
    function draw(){
      var xc=data.columns.indexOf(sx.value),yc=data.columns.indexOf(sy.value);
      var sc=ss.value===''?-1:data.columns.indexOf(ss.value);
      var series={},order=[];
      data.rows.forEach(function(r){
        var x=r[xc],y=r[yc];
        if(typeof x!=='number'||typeof y!=='number')return;
        if(sl.checked&&y<=0)return;
        var s=sc<0?'':String(r[sc]);
        if(!(s in series)){series[s]=[];order.push(s);}
        series[s].push([x,y]);
      });
      var W=760,H=420,L=90,R=190,T=30,B=50;
      var svg=el('svg',{width:W,height:H,viewBox:'0 0 '+W+' '+H,'font-size':12,'font-family':'sans-serif'});
      svg.appendChild(el('rect',{width:W,height:H,fill:'white'}));
      var xs=[],ys=[];
      order.forEach(function(s){series[s].forEach(function(p){xs.push(p[0]);ys.push(p[1]);});});
      if(xs.length===0){svg.appendChild(el('text',{x:W/2,y:H/2,'text-anchor':'middle'},'no numeric values to plot'));}
      else{
        var ty=function(v){return sl.checked?Math.log10(v):v;};
        var x0=Math.min.apply(null,xs),x1=Math.max.apply(null,xs);
        var y0=Math.min.apply(null,ys.map(ty)),y1=Math.max.apply(null,ys.map(ty));
        if(!sl.checked)y0=Math.min(0,y0);
        if(x1===x0){x0-=1;x1+=1;}if(y1===y0){y1=y0+1;}
        var px=function(x){return L+(x-x0)/(x1-x0)*(W-L-R);};
        var py=function(y){return H-B-(ty(y)-y0)/(y1-y0)*(H-T-B);};
        for(var i=0;i<=5;i++){
          var v=y0+(y1-y0)*i/5,yy=H-B-(H-T-B)*i/5;
          svg.appendChild(el('line',{x1:L,x2:W-R,y1:yy,y2:yy,stroke:'#e5e5e5'}));
          svg.appendChild(el('text',{x:L-6,y:yy+4,'text-anchor':'end'},fmt(sl.checked?Math.pow(10,v):v)));
        }
        var seen={};
        xs.forEach(function(x){if(seen[x])return;seen[x]=1;
          svg.appendChild(el('line',{x1:px(x),x2:px(x),y1:T,y2:H-B,stroke:'#f0f0f0'}));
          svg.appendChild(el('text',{x:px(x),y:H-B+16,'text-anchor':'middle'},fmt(x)));});
        svg.appendChild(el('rect',{x:L,y:T,width:W-L-R,height:H-T-B,fill:'none',stroke:'#333'}));
        var colours=['#1f77b4','#ff7f0e','#2ca02c','#d62728','#9467bd','#8c564b','#e377c2','#7f7f7f','#bcbd22','#17becf'];
        order.forEach(function(s,k){
          var pts=series[s].sort(function(a,b){return a[0]-b[0];});
          var c=colours[k%10];
          svg.appendChild(el('polyline',{points:pts.map(function(p){return px(p[0])+','+py(p[1]);}).join(' '),fill:'none',stroke:c,'stroke-width':2}));
          pts.forEach(function(p){svg.appendChild(el('circle',{cx:px(p[0]),cy:py(p[1]),r:3,fill:c}));});
          if(sc>=0){
            var ly=T+10+18*k;
            svg.appendChild(el('line',{x1:W-R+12,x2:W-R+34,y1:ly,y2:ly,stroke:c,'stroke-width':2}));
            svg.appendChild(el('text',{x:W-R+40,y:ly+4},ss.value+' = '+s));
          }
        });
      }
      var unit=function(name){var u=data.units[data.columns.indexOf(name)];return u?' ('+u+')':'';};
      svg.appendChild(el('text',{x:(L+W-R)/2,y:H-12,'text-anchor':'middle'},sx.value+unit(sx.value)));
      svg.appendChild(el('text',{transform:'translate(18,'+((T+H-B)/2)+') rotate(-90)','text-anchor':'middle'},
        sy.value+unit(sy.value)+(sl.checked?' (log scale)':'')));
      holder.innerHTML='';
      holder.appendChild(svg);
    }
    [sx,sy,ss,sl].forEach(function(e){e.addEventListener('change',draw);});
    draw();
  });
})();
)";

void report_html_table(std::string& out, const Table& t, int& counter) {
  const std::string id = fmt::format("t{}-{}", counter++, t.id.empty() ? "table" : t.id);
  if (!t.title.empty()) out += "<h3>" + html_escape(t.title) + "</h3>\n";
  if (t.rows.size() > 12) {
    out += fmt::format(
        "<input class=\"search\" type=\"search\" placeholder=\"Search {} rows\" "
        "data-table=\"{}\">\n",
        t.rows.size(), id);
  }
  const bool scroll = t.rows.size() > 40;
  out += scroll ? "<div class=\"wide scroll\">" : "<div class=\"wide\">";
  out += "<table class=\"report\" id=\"" + id + "\"><thead><tr>";
  for (const Column& c : t.columns) {
    std::string tip = c.description;
    if (!c.unit.empty()) tip += (tip.empty() ? "" : " ") + std::string("[") + c.unit + "]";
    const std::string heading = c.heading.empty() ? c.name : c.heading;
    out += "<th" + std::string(c.right_aligned() ? " class=\"num\"" : "") +
           (tip.empty() ? "" : " title=\"" + html_escape(tip) + "\"") + ">" + html_escape(heading);
    if (c.heading.empty() && !c.unit.empty()) {
      out += " <span class=\"unit\">(" + html_escape(c.unit) + ")</span>";
    }
    out += "</th>";
  }
  out += "</tr></thead>\n<tbody>\n";
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    out += "<tr>";
    for (std::size_t k = 0; k < t.columns.size(); ++k) {
      const Cell& cell = t.rows[r][k];
      const std::optional<double> n = cell.number();
      std::string attrs;
      if (t.columns[k].right_aligned()) attrs += " class=\"num\"";
      if (n && std::isfinite(*n)) attrs += fmt::format(" data-n=\"{:.17g}\"", *n);
      std::string shown = html_escape(t.shown(r, k));
      if (t.columns[k].kind == Kind::code && !cell.is_missing())
        shown = "<code>" + shown + "</code>";
      out += "<td" + attrs + ">" + shown + "</td>";
    }
    out += "</tr>\n";
  }
  out += "</tbody></table>\n";
  out += "</div>\n";
  if (!t.caption.empty()) out += "<p>" + html_escape(t.caption) + "</p>\n";
}

}  // namespace

std::string html(const Report& report) {
  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<title>" +
      html_escape(report.title) + "</title>\n<style>" + kReportStyle +
      "</style>\n</head>\n<body>\n";
  out += "<header><h1>" + html_escape(report.title) + "</h1>";
  if (!report.subtitle.empty()) out += "<p>" + html_escape(report.subtitle) + "</p>";
  out += "</header>\n<nav>";
  for (const Section& s : report.sections) {
    if (!s.title.empty())
      out += "<a href=\"#" + html_escape(s.id) + "\">" + html_escape(s.title) + "</a>";
  }
  out += "</nav>\n<main>\n";
  int counter = 0;
  for (const Section& s : report.sections) {
    out += "<section id=\"" + html_escape(s.id) + "\">\n";
    if (!s.title.empty()) out += "<h2>" + html_escape(s.title) + "</h2>\n";
    for (const Block& b : s.blocks) {
      if (const auto* p = std::get_if<Paragraph>(&b)) {
        out += "<p>" + html_escape(p->text) + "</p>\n";
      } else if (const auto* t = std::get_if<Table>(&b)) {
        report_html_table(out, *t, counter);
      } else if (const auto* f = std::get_if<Figure>(&b)) {
        out += "<figure id=\"" + html_escape(f->id) + "\">";
        if (!f->title.empty()) out += "<h3>" + html_escape(f->title) + "</h3>";
        out += "<img src=\"data:" + f->mime + ";base64," + base64(f->bytes) + "\" alt=\"" +
               html_escape(f->alt.empty() ? f->title : f->alt) + "\">";
        if (!f->caption.empty()) out += "<figcaption>" + html_escape(f->caption) + "</figcaption>";
        out += "</figure>\n";
      } else if (const auto* n = std::get_if<Note>(&b)) {
        out += std::string("<div class=\"note") +
               (n->level == Note::Level::warning ? " warning\"><b>Warning:</b> " : "\">") +
               html_escape(n->text) + "</div>\n";
      } else if (const auto* pre = std::get_if<Preformatted>(&b)) {
        out += "<pre>" + html_escape(pre->text) + "</pre>\n";
      } else if (const auto* raw = std::get_if<RawHtml>(&b)) {
        out += raw->html + "\n";
      }
    }
    out += "</section>\n";
  }
  out += "</main>\n<script>" + std::string(kReportScript) + "</script>\n</body></html>\n";
  return out;
}

namespace {

std::string svg_head(int w, int h) {
  return fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} "
      "{1}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
      "fill=\"white\"/>\n",
      w, h);
}

std::string report_number(double v) {
  const double a = std::fabs(v);
  if (a < 1e-9) return "0";
  if (a >= 1e4 && a < 1e12) return fmt::format("{:.0f}", v);
  if (a >= 1e12 || a < 1e-3) return fmt::format("{:.3g}", v);
  return fmt::format("{:.4g}", v);
}

// The smallest of 1, 2, 2.5, 5 times a power of ten at least `v`: an axis's end.
double report_nice_ceiling(double v) {
  if (v <= 0) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * p >= v * (1 - 1e-12)) return m * p;
  }
  return 10 * p;
}

}  // namespace

std::string svg_bar_chart(const std::string& title, const std::vector<Bar>& bars,
                          const std::string& unit, int highlight, double axis_end) {
  const int L = 150, R = 220, T = 34, row = 22, W = 760;
  const int H = T + row * static_cast<int>(bars.size()) + 40;
  double peak = 0;
  for (const Bar& b : bars) peak = std::max(peak, b.value);
  peak = axis_end > 0 ? std::max(axis_end, peak) : report_nice_ceiling(peak);
  std::string svg = svg_head(W, H);
  svg += fmt::format("<text x=\"{}\" y=\"20\" font-size=\"14\" text-anchor=\"middle\">{}</text>\n",
                     W / 2, html_escape(title));
  for (std::size_t k = 0; k < bars.size(); ++k) {
    const Bar& b = bars[k];
    const int y = T + row * static_cast<int>(k);
    const double w = b.value / peak * (W - L - R);
    svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>\n", L - 8, y + 15,
                       html_escape(b.label));
    svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{}\" fill=\"{}\"/>\n", L,
                       y + 3, std::max(w, 0.5), row - 6,
                       static_cast<int>(k) == highlight ? "#d9822b" : "#4a78b5");
    svg +=
        fmt::format("<text x=\"{:.1f}\" y=\"{}\">{}{}</text>\n", L + std::max(w, 0.5) + 6, y + 15,
                    report_number(b.value), b.note.empty() ? "" : "  " + html_escape(b.note));
  }
  const int axis = T + row * static_cast<int>(bars.size()) + 4;
  svg += fmt::format("<line x1=\"{}\" x2=\"{}\" y1=\"{}\" y2=\"{}\" stroke=\"#333\"/>\n", L, W - R,
                     axis, axis);
  for (int i = 0; i <= 4; ++i) {
    const double x = L + (W - L - R) * i / 4.0;
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", x,
                       axis + 16, report_number(peak * i / 4.0));
  }
  svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", (L + W - R) / 2,
                     axis + 32, html_escape(unit));
  return svg + "</svg>\n";
}

std::string svg_memory_map(const std::string& title, const std::vector<Part>& parts, double total,
                           const std::string& unit) {
  const int W = 900, L = 20, R = 20, T = 34, lane_h = 34;
  static const char* colours[] = {"#4a78b5", "#d9822b", "#5aa469", "#c44e52", "#8172b2",
                                  "#937860", "#da8bc3", "#8c8c8c", "#ccb974", "#64b5cd"};
  // Lanes: each part on the first lane where it overlaps nothing.
  std::vector<std::vector<std::pair<double, double>>> lanes;
  std::vector<int> lane_of(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const double a = parts[k].start, b = parts[k].start + parts[k].size;
    std::size_t l = 0;
    for (; l < lanes.size(); ++l) {
      bool clash = false;
      for (const auto& [x, y] : lanes[l]) clash = clash || (a < y && x < b);
      if (!clash) break;
    }
    if (l == lanes.size()) lanes.emplace_back();
    lanes[l].push_back({a, b});
    lane_of[k] = static_cast<int>(l);
  }
  const int nl = std::max<int>(1, static_cast<int>(lanes.size()));
  const int legend_rows = (static_cast<int>(parts.size()) + 1 + 3) / 4;
  const int H = T + lane_h * nl + 34 + 18 * legend_rows + 10;
  const double scale = total > 0 ? (W - L - R) / total : 0;
  std::string svg = svg_head(W, H);
  svg += fmt::format("<text x=\"{}\" y=\"20\" font-size=\"14\" text-anchor=\"middle\">{}</text>\n",
                     W / 2, html_escape(title));
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#eeeeee\"/>\n", L,
                     T, W - L - R, lane_h * nl);
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const double x = L + parts[k].start * scale, w = parts[k].size * scale;
    const int y = T + lane_of[k] * lane_h;
    svg += fmt::format(
        "<rect x=\"{:.2f}\" y=\"{}\" width=\"{:.2f}\" height=\"{}\" fill=\"{}\" stroke=\"white\" "
        "stroke-width=\"0.5\"><title>{}: {} {} from {}</title></rect>\n",
        x, y + 2, w, lane_h - 4, colours[k % 10], html_escape(parts[k].label),
        report_number(parts[k].size), html_escape(unit), report_number(parts[k].start));
    if (w > 7.0 * static_cast<double>(parts[k].label.size()) + 4) {
      svg += fmt::format(
          "<text x=\"{:.2f}\" y=\"{}\" text-anchor=\"middle\" fill=\"white\" "
          "font-size=\"11\">{}</text>\n",
          x + w / 2, y + lane_h / 2 + 4, html_escape(parts[k].label));
    }
  }
  const int axis = T + lane_h * nl;
  svg += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n", L, T,
      W - L - R, lane_h * nl);
  for (int i = 0; i <= 8; ++i) {
    const double v = total * i / 8.0;
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"{}\">{}</text>\n", L + v * scale,
                       axis + 15,
                       i == 0   ? "start"
                       : i == 8 ? "end"
                                : "middle",
                       report_number(v));
  }
  svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", W / 2, axis + 30,
                     html_escape(unit));
  for (std::size_t k = 0; k <= parts.size(); ++k) {
    const int col = static_cast<int>(k) % 4, row = static_cast<int>(k) / 4;
    const int lx = L + col * 215, ly = axis + 52 + 18 * row;
    const bool free = k == parts.size();
    double covered = 0;
    if (free) {
      std::vector<std::pair<double, double>> all;
      for (const Part& p : parts) all.push_back({p.start, p.start + p.size});
      std::sort(all.begin(), all.end());
      double end = 0;
      for (const auto& [a, b] : all) {
        if (b > end) covered += b - std::max(a, end), end = b;
      }
    }
    svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"12\" height=\"12\" fill=\"{}\"/>\n", lx,
                       ly - 10, free ? "#eeeeee" : colours[k % 10]);
    svg += fmt::format("<text x=\"{}\" y=\"{}\">{} ({} {})</text>\n", lx + 18, ly,
                       free ? std::string("free") : html_escape(parts[k].label),
                       report_number(free ? std::max(0.0, total - covered) : parts[k].size),
                       html_escape(unit));
  }
  return svg + "</svg>\n";
}

std::string svg_timeline(const std::string& title, const std::vector<Track>& tracks,
                         double end_seconds) {
  const int L = 130, R = 20, T = 34, row = 14, W = 900, columns = 375;
  int groups = 0;
  for (std::size_t k = 0; k < tracks.size(); ++k)
    groups += k == 0 || tracks[k].group != tracks[k - 1].group;
  const int H = T + row * static_cast<int>(tracks.size()) + 6 * groups + 64;
  std::string svg = svg_head(W, H);
  svg += fmt::format("<text x=\"{}\" y=\"20\" font-size=\"14\" text-anchor=\"middle\">{}</text>\n",
                     W / 2, html_escape(title));
  const double span = end_seconds > 0 ? end_seconds : 1;
  const double cw = static_cast<double>(W - L - R) / columns;
  int y = T;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    if (k == 0 || tracks[k].group != tracks[k - 1].group) y += 6;
    std::vector<double> busy(columns, 0.0);
    for (const auto& [a, b] : tracks[k].intervals) {
      const double s = std::clamp(a / span, 0.0, 1.0) * columns;
      const double e = std::clamp(b / span, 0.0, 1.0) * columns;
      for (int c = static_cast<int>(s); c < columns && c < e; ++c) {
        busy[c] += std::min<double>(e, c + 1) - std::max<double>(s, c);
      }
    }
    svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"end\" font-size=\"11\">{}</text>\n",
                       L - 6, y + row - 3, html_escape(tracks[k].name));
    svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#f3f3f3\"/>\n", L,
                       y + 1, W - L - R, row - 2);
    for (int c = 0; c < columns; ++c) {
      const double f = std::min(1.0, busy[c]);
      if (f <= 0) continue;
      // White to dark blue with the share of the column's time busy.
      const int r = static_cast<int>(243 - f * (243 - 32));
      const int g = static_cast<int>(243 - f * (243 - 72));
      const int bl = static_cast<int>(243 - f * (243 - 150));
      svg += fmt::format(
          "<rect x=\"{:.2f}\" y=\"{}\" width=\"{:.2f}\" height=\"{}\" fill=\"rgb({},{},{})\"/>\n",
          L + c * cw, y + 1, cw + 0.05, row - 2, r, g, bl);
    }
    y += row;
  }
  y += 4;
  svg += fmt::format("<line x1=\"{}\" x2=\"{}\" y1=\"{}\" y2=\"{}\" stroke=\"#333\"/>\n", L, W - R,
                     y, y);
  for (int i = 0; i <= 5; ++i) {
    const double x = L + (W - L - R) * i / 5.0;
    svg +=
        fmt::format("<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#333\"/>\n",
                    x, y, y + 4);
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", x, y + 17,
                       report_number(span * 1e3 * i / 5.0));
  }
  svg += fmt::format(
      "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">simulated time (ms); shade: share of each "
      "{:.3g} us column the unit was busy (white idle, dark blue busy)</text>\n",
      (L + W - R) / 2, y + 36, span * 1e6 / columns);
  return svg + "</svg>\n";
}

std::string html_plot(const Table& data, const std::vector<std::string>& x_choices,
                      const std::string& y_default) {
  nlohmann::json doc;
  doc["columns"] = nlohmann::json::array();
  doc["units"] = nlohmann::json::array();
  for (const Column& c : data.columns) {
    doc["columns"].push_back(c.csv_key());
    doc["units"].push_back(c.unit);
  }
  doc["rows"] = nlohmann::json::array();
  for (const auto& row : data.rows) {
    nlohmann::json r = nlohmann::json::array();
    for (const Cell& c : row) {
      if (const auto n = c.number(); n && std::isfinite(*n)) {
        r.push_back(*n);
      } else if (const auto* s = std::get_if<std::string>(&c.value)) {
        r.push_back(*s);
      } else {
        r.push_back(nullptr);
      }
    }
    doc["rows"].push_back(r);
  }
  std::string json = doc.dump();
  // Inside <script>: no "</" may end it early.
  std::string safe;
  for (std::size_t i = 0; i < json.size(); ++i) {
    if (json[i] == '<') {
      safe += "\\u003c";
    } else {
      safe += json[i];
    }
  }
  auto options = [&](const std::vector<std::string>& names, const std::string& chosen, bool none) {
    std::string out = none ? "<option value=\"\">(none)</option>" : "";
    for (const std::string& n : names) {
      out += "<option" + std::string(n == chosen ? " selected" : "") + " value=\"" +
             html_escape(n) + "\">" + html_escape(n) + "</option>";
    }
    return out;
  };
  std::vector<std::string> numeric;
  for (std::size_t k = 0; k < data.columns.size(); ++k) {
    bool any = false;
    for (const auto& row : data.rows) any = any || row[k].number().has_value();
    if (any) numeric.push_back(data.columns[k].csv_key());
  }
  const std::string x = x_choices.empty() ? std::string() : x_choices[0];
  const std::string series = x_choices.size() > 1 ? x_choices[1] : std::string();
  std::string out = "<div class=\"plot\"><script type=\"application/json\">" + safe + "</script>\n";
  out += "<label>x <select class=\"x\">" + options(x_choices, x, false) + "</select></label>";
  out += "<label>y <select class=\"y\">" + options(numeric, y_default, false) + "</select></label>";
  out += "<label>lines by <select class=\"series\">" + options(x_choices, series, true) +
         "</select></label>";
  out += "<label><input class=\"logy\" type=\"checkbox\"> log y</label>";
  out += "<div class=\"chart\"></div></div>";
  return out;
}

}  // namespace pp5::report
