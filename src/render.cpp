#include "budjam/render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace budjam {

namespace {

// Fixed-precision numbers keep the document deterministic and compact.
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Periodic shifts (in box units) of an object whose bounding box is [x0, x1] × [y0, y1] that
// intersect the box [0, L]²; with Lees–Edwards shear an image one box up is shifted by γL in x.
std::vector<std::array<double, 2>> images(double x0, double x1, double y0, double y1, const Box& box, bool periodic) {
  std::vector<std::array<double, 2>> out;
  const double L = box.L;
  for (int sy = -1; sy <= 1; ++sy)
    for (int sx = -1; sx <= 1; ++sx) {
      if (!periodic && (sx != 0 || sy != 0)) continue;
      const double dx = sx * L + sy * box.shear * L, dy = sy * L;
      if (x1 + dx < 0 || x0 + dx > L || y1 + dy < 0 || y0 + dy > L) continue;
      out.push_back({dx, dy});
    }
  return out;
}

double wrap(double v, double L) { return v - L * std::floor(v / L); }

// Where the parts of the picture go, in pixels: the box (side × side) inside a margin, then the
// legend and the caption lines below it.
struct Layout {
  double margin, side, legend_h, caption_h, width, height;
  std::vector<std::string> caption_lines;
  Layout(double L, const RenderOptions& opt)
      : margin(opt.margin * opt.pixels_per_unit), side(L * opt.pixels_per_unit), legend_h(opt.legend ? 44.0 : 0.0) {
    for (std::size_t a = 0; !opt.caption.empty() && a <= opt.caption.size();) {
      const std::size_t b = std::min(opt.caption.find('\n', a), opt.caption.size());
      caption_lines.push_back(opt.caption.substr(a, b - a));
      a = b + 1;
    }
    caption_h = 16.0 * static_cast<double>(caption_lines.size()) + (caption_lines.empty() ? 0.0 : 6.0);
    width = side + 2 * margin;
    height = side + 2 * margin + legend_h + caption_h;
  }
};

}  // namespace

RenderSize render_size(double L, const RenderOptions& options) {
  const Layout layout(L, options);
  return {layout.width, layout.height};
}

std::string force_colour(double f, double f_max) {
  // Ramp through pale yellow → orange → red → dark red (YlOrRd-like), linear in f/f_max.
  static constexpr std::array<std::array<double, 3>, 5> stops{
      {{255, 237, 160}, {254, 178, 76}, {240, 59, 32}, {189, 0, 38}, {103, 0, 13}}};
  double t = (f_max > 0 && f > 0) ? std::min(1.0, f / f_max) : 0.0;
  const double s = t * (stops.size() - 1);
  const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(s), stops.size() - 2);
  const double w = s - static_cast<double>(k);
  char buf[8];
  std::array<int, 3> c{};
  for (int i = 0; i < 3; ++i) c[i] = static_cast<int>(std::lround(stops[k][i] + w * (stops[k + 1][i] - stops[k][i])));
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string render_svg(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                       const RenderOptions& opt) {
  const std::size_t n = p.size();
  if (net.rattler.size() != n || net.lobe_contacts.size() != 2 * n)
    throw std::invalid_argument("render_svg: the contact network does not belong to this packing");
  if (!(p.box.L > 0)) throw std::invalid_argument("render_svg: box side must be positive");
  for (const auto& c : contacts)
    if (c.i >= 2 * n || c.j >= 2 * n)
      throw std::invalid_argument("render_svg: contact names a lobe that does not exist");

  const double L = p.box.L, s = opt.pixels_per_unit;
  const Layout layout(L, opt);
  const double m = layout.margin, side = layout.side, legend_h = layout.legend_h, W = layout.width, H = layout.height;
  const std::vector<std::string>& caption_lines = layout.caption_lines;
  // Box coordinates → pixels (y up in the model, down in SVG).
  auto X = [&](double x) { return m + x * s; };
  auto Y = [&](double y) { return m + (L - y) * s; };

  Lobes lobes;
  place_lobes(p, lobes);
  // Each cell is drawn around its centroid wrapped into the box, so its two lobes stay together.
  std::vector<double> lx(2 * n), ly(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double cx = wrap(p.x(i), L), cy = wrap(p.y(i), L);
    for (std::size_t l : {mother_lobe(i), bud_lobe(i)}) {
      lx[l] = lobes.x[l] - p.x(i) + cx;
      ly[l] = lobes.y[l] - p.y(i) + cy;
    }
  }

  std::string o;
  o.reserve(256 * n + 128 * contacts.size() + 2048);
  o += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  o += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W) + "\" height=\"" + num(H) + "\" viewBox=\"0 0 " +
       num(W) + " " + num(H) + "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  o += "<!-- budjam packing: N=" + std::to_string(n) + " L=" + num(L) + " contacts=" + std::to_string(contacts.size()) +
       " rattlers=" + std::to_string(net.N_f) + " unconstrained_buds=" + std::to_string(net.N_u_buds) + " -->\n";
  o += "<defs><clipPath id=\"box\"><rect x=\"" + num(m) + "\" y=\"" + num(m) + "\" width=\"" + num(side) +
       "\" height=\"" + num(side) + "\"/></clipPath></defs>\n";
  o += "<rect x=\"0\" y=\"0\" width=\"" + num(W) + "\" height=\"" + num(H) + "\" fill=\"white\"/>\n";
  o += "<rect x=\"" + num(m) + "\" y=\"" + num(m) + "\" width=\"" + num(side) + "\" height=\"" + num(side) +
       "\" fill=\"#f7f7f7\" stroke=\"black\" stroke-width=\"1\"/>\n";

  // Cells: mothers and buds, non-rattlers in blue tones, rattlers grey; unconstrained buds get a
  // dashed green outline.
  o += "<g clip-path=\"url(#box)\" stroke-width=\"1\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    const bool rattler = net.rattler[i];
    for (std::size_t l : {mother_lobe(i), bud_lobe(i)}) {
      const double R = lobes.R[l];
      const bool bud = is_bud(l);
      const bool free_bud = bud && net.unconstrained_bud(i);
      std::string cls = rattler ? (bud ? "bud rattler" : "mother rattler") : (bud ? "bud" : "mother");
      if (free_bud) cls += " unconstrained";
      const char* fill = rattler ? "#d9d9d9" : (bud ? "#bcbddc" : "#c6dbef");
      const char* stroke = free_bud ? "#1a9641" : (rattler ? "#969696" : (bud ? "#756bb1" : "#3182bd"));
      const std::string extra = free_bud ? " stroke-dasharray=\"3,2\" stroke-width=\"2\"" : "";
      for (const auto& d : images(lx[l] - R, lx[l] + R, ly[l] - R, ly[l] + R, p.box, opt.periodic_images))
        o += "<circle class=\"" + cls + "\" data-cell=\"" + std::to_string(i) + "\" cx=\"" + num(X(lx[l] + d[0])) +
             "\" cy=\"" + num(Y(ly[l] + d[1])) + "\" r=\"" + num(R * s) + "\" fill=\"" + fill + "\" stroke=\"" +
             stroke + "\"" + extra + "/>\n";
    }
  }
  o += "</g>\n";

  // Mother–bud links: which bud belongs to which mother, also where lobes of different cells touch.
  o += "<g clip-path=\"url(#box)\" stroke=\"#252525\" stroke-width=\"1.5\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    const double x0 = lx[mother_lobe(i)], y0 = ly[mother_lobe(i)], x1 = lx[bud_lobe(i)], y1 = ly[bud_lobe(i)];
    for (const auto& d :
         images(std::min(x0, x1), std::max(x0, x1), std::min(y0, y1), std::max(y0, y1), p.box, opt.periodic_images))
      o += "<line class=\"link\" data-link=\"" + std::to_string(i) + "\" x1=\"" + num(X(x0 + d[0])) + "\" y1=\"" +
           num(Y(y0 + d[1])) + "\" x2=\"" + num(X(x1 + d[0])) + "\" y2=\"" + num(Y(y1 + d[1])) + "\"/>\n";
  }
  o += "</g>\n";

  double f_max = 0;
  for (const auto& c : contacts) f_max = std::max(f_max, c.force());
  if (opt.draw_contacts) {
    o += "<g clip-path=\"url(#box)\" stroke-linecap=\"round\">\n";
    for (const auto& c : contacts) {
      // From lobe i to the image of lobe j nearest to it: n points from j to i.
      const double x0 = lx[c.i], y0 = ly[c.i];
      const double x1 = x0 - c.r * c.nx, y1 = y0 - c.r * c.ny;
      const bool bearing = !net.rattler[cell_of(c.i)] && !net.rattler[cell_of(c.j)];
      const std::string colour = bearing ? force_colour(c.force(), f_max) : "#969696";
      const double width = bearing ? 1.0 + 3.0 * (f_max > 0 ? c.force() / f_max : 0.0) : 0.75;
      for (const auto& d :
           images(std::min(x0, x1), std::max(x0, x1), std::min(y0, y1), std::max(y0, y1), p.box, opt.periodic_images))
        o += std::string("<line class=\"") + (bearing ? "contact" : "contact rattler") + "\" x1=\"" +
             num(X(x0 + d[0])) + "\" y1=\"" + num(Y(y0 + d[1])) + "\" x2=\"" + num(X(x1 + d[0])) + "\" y2=\"" +
             num(Y(y1 + d[1])) + "\" stroke=\"" + colour + "\" stroke-width=\"" + num(width) + "\"/>\n";
    }
    o += "</g>\n";
  }

  double y = m + side + 6;
  if (opt.legend) {
    // Force scale bar and the meaning of the marks.
    const double bar_w = std::min(160.0, side * 0.5);
    const int seg = 20;
    o += "<g class=\"legend\">\n";
    for (int k = 0; k < seg; ++k)
      o += "<rect x=\"" + num(m + bar_w * k / seg) + "\" y=\"" + num(y) + "\" width=\"" + num(bar_w / seg + 0.5) +
           "\" height=\"10\" fill=\"" + force_colour((k + 0.5) / seg, 1.0) + "\"/>\n";
    char buf[64];
    std::snprintf(buf, sizeof buf, "f/k: 0 to %.3g", f_max);
    o += "<text x=\"" + num(m) + "\" y=\"" + num(y + 24) + "\">" + escape(buf) + "</text>\n";
    const double lx0 = m + bar_w + 16;
    o += "<circle cx=\"" + num(lx0 + 6) + "\" cy=\"" + num(y + 5) +
         "\" r=\"5\" fill=\"#bcbddc\" stroke=\"#1a9641\" stroke-dasharray=\"3,2\" stroke-width=\"2\"/>\n";
    o += "<text x=\"" + num(lx0 + 16) + "\" y=\"" + num(y + 9) + "\">unconstrained bud</text>\n";
    o += "<circle cx=\"" + num(lx0 + 6) + "\" cy=\"" + num(y + 25) +
         "\" r=\"5\" fill=\"#d9d9d9\" stroke=\"#969696\"/>\n";
    o += "<text x=\"" + num(lx0 + 16) + "\" y=\"" + num(y + 29) + "\">rattler</text>\n";
    o += "</g>\n";
    y += legend_h;
  }
  for (const auto& line : caption_lines) {
    o += "<text class=\"caption\" x=\"" + num(m) + "\" y=\"" + num(y + 12) + "\">" + escape(line) + "</text>\n";
    y += 16.0;
  }
  o += "</svg>\n";
  return o;
}

}  // namespace budjam
