// SVG pictures of a hand-made packing: lobes, periodic images, contacts coloured by force,
// rattlers and unconstrained buds.
#include "budjam/render.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <regex>
#include <string>

using namespace budjam;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t k = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++k;
  return k;
}

// L = 4. Cell 0: bud (b = 0.5) pointing +x, mother at (1.85, 2), bud at (2.6, 2).
// Cell 1: mother at (3.2, 2) touching the bud of cell 0 (r = 0.6 < σ = 0.75, f = 0.15); its bud at
// (3.95, 2) crosses the right edge. Cell 2: a rattler far away. Cell 3: a newborn whose mother at
// (0.6, 2) (image 4.6) touches cell 1's bud across the boundary (r = 0.65, f = 0.1); its bud is free.
struct Scene3 {
  Packing p;
  std::vector<Contact> contacts;
  ContactNetwork net;
};

Scene3 make() {
  Scene3 s;
  s.p.box.L = 4.0;
  const auto d = Dumbbell::of(0.5);  // mother offset 0.15, bud offset 0.6
  s.p.add_cell(1.85 + d.mother_offset, 2.0, 0.0, 0.5, 0.002, -1);
  s.p.add_cell(3.2 + d.mother_offset, 2.0, 0.0, 0.5, 0.002, -1);
  s.p.add_cell(1.0, 3.3, 1.0, 0.3, 0.002, -1);
  const auto n3 = Dumbbell::of(0.01);
  s.p.add_cell(0.6, 2.0 + n3.mother_offset, std::numbers::pi / 2, 0.01, 0.002, -1);
  // contact A: bud of 0 (lobe 1) with mother of 1 (lobe 2); n from j to i = (−1, 0)
  s.contacts.push_back(Contact{1, 2, -1.0, 0.0, 0.6, 0.75});
  // contact B: bud of 1 (lobe 3, x = 3.95) with mother of 3 (lobe 6, image at 4.6); n = (−1, 0)
  s.contacts.push_back(Contact{3, 6, -1.0, 0.0, 0.65, 0.75});
  s.net.N = 4;
  s.net.rattler = {false, false, true, false};
  s.net.lobe_contacts = {0, 1, 1, 1, 0, 0, 1, 0};
  s.net.N_f = 1;
  s.net.N_nr = 3;
  s.net.N_u_buds = 1;
  return s;
}

}  // namespace

TEST_CASE("render draws every lobe once plus the periodic images of lobes crossing the boundary") {
  auto s = make();
  const std::string svg = render_svg(s.p, s.contacts, s.net);
  CHECK(svg.rfind("<?xml", 0) == 0);
  CHECK(svg.substr(svg.size() - 7) == "</svg>\n");
  CHECK(count(svg, "<g") == count(svg, "</g>"));
  CHECK(count(svg, "data-cell=\"0\"") == 2);
  CHECK(count(svg, "data-cell=\"1\"") == 3);  // mother, bud, bud's image at the left edge
  CHECK(count(svg, "data-cell=\"3\"") == 2);
  RenderOptions flat;
  flat.periodic_images = false;
  CHECK(count(render_svg(s.p, s.contacts, s.net, flat), "data-cell=\"1\"") == 2);
}

TEST_CASE("render places lobes at their centres in pixels, y pointing up") {
  auto s = make();
  RenderOptions o;
  o.pixels_per_unit = 100;
  o.margin = 0.5;  // 50 px
  const std::string svg = render_svg(s.p, s.contacts, s.net, o);
  // mother of cell 0 at (1.85, 2): cx = 50 + 185, cy = 50 + (4 − 2)·100, r = 50
  CHECK(svg.find("class=\"mother\" data-cell=\"0\" cx=\"235.00\" cy=\"250.00\" r=\"50.00\"") != std::string::npos);
  // bud of cell 1 at x = 3.95 and its image at −0.05, radius 25
  CHECK(svg.find("data-cell=\"1\" cx=\"445.00\" cy=\"250.00\" r=\"25.00\"") != std::string::npos);
  CHECK(svg.find("data-cell=\"1\" cx=\"45.00\" cy=\"250.00\" r=\"25.00\"") != std::string::npos);
  // contact B from the bud of 1 (x = 3.95) to the image of the mother of 3 (x = 4.6), and its copy
  CHECK(svg.find("x1=\"445.00\" y1=\"250.00\" x2=\"510.00\" y2=\"250.00\"") != std::string::npos);
  CHECK(svg.find("x1=\"45.00\" y1=\"250.00\" x2=\"110.00\" y2=\"250.00\"") != std::string::npos);
}

TEST_CASE("render links every bud to its own mother, so lineages are visible") {
  auto s = make();
  RenderOptions o;
  o.pixels_per_unit = 100;
  o.margin = 0.5;  // 50 px
  o.periodic_images = false;
  const std::string svg = render_svg(s.p, s.contacts, s.net, o);
  CHECK(count(svg, "class=\"link\"") == 4);
  // cell 0: mother (1.85, 2) to bud (2.6, 2); cell 1: mother (3.2, 2) to bud (3.95, 2)
  CHECK(svg.find("data-link=\"0\" x1=\"235.00\" y1=\"250.00\" x2=\"310.00\" y2=\"250.00\"") != std::string::npos);
  CHECK(svg.find("data-link=\"1\" x1=\"370.00\" y1=\"250.00\" x2=\"445.00\" y2=\"250.00\"") != std::string::npos);
}

TEST_CASE("render marks rattlers and unconstrained buds") {
  auto s = make();
  const std::string svg = render_svg(s.p, s.contacts, s.net);
  CHECK(count(svg, "class=\"mother rattler\"") == 1);
  CHECK(count(svg, "class=\"bud rattler\"") == 1);  // a rattler's free bud is not "unconstrained"
  CHECK(count(svg, "class=\"bud unconstrained\" data-cell=\"3\"") == 1);
  CHECK(count(svg, "unconstrained\" data-cell") == 1);
}

TEST_CASE("render colours contacts by force and draws the images of contacts across the boundary") {
  auto s = make();
  const std::string svg = render_svg(s.p, s.contacts, s.net);
  // contact A (f = 0.15 = f_max) once; contact B (f = 0.1 = 2 f_max/3) twice: it crosses x = L.
  CHECK(count(svg, "class=\"contact\"") == 3);
  CHECK(count(svg, "stroke=\"" + force_colour(1.0, 1.0) + "\"") == 1);
  CHECK(count(svg, "stroke=\"" + force_colour(2.0 / 3.0, 1.0) + "\"") == 2);
  RenderOptions none;
  none.draw_contacts = false;
  CHECK(count(render_svg(s.p, s.contacts, s.net, none), "class=\"contact") == 0);
}

TEST_CASE("force colours darken monotonically from weakest to strongest") {
  auto lum = [](const std::string& c) {
    const int r = std::stoi(c.substr(1, 2), nullptr, 16), g = std::stoi(c.substr(3, 2), nullptr, 16),
              b = std::stoi(c.substr(5, 2), nullptr, 16);
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
  };
  CHECK(force_colour(0.0, 1.0) == "#ffeda0");
  CHECK(force_colour(1.0, 1.0) == "#67000d");
  CHECK(force_colour(5.0, 1.0) == force_colour(1.0, 1.0));
  double prev = 1e9;
  for (int k = 0; k <= 20; ++k) {
    const double l = lum(force_colour(k / 20.0, 1.0));
    CHECK(l < prev);
    prev = l;
  }
}

TEST_CASE("render is deterministic and refuses a network of another packing") {
  auto s = make();
  RenderOptions o;
  o.caption = "phi = 0.8 & <test>\nsecond line";
  const std::string a = render_svg(s.p, s.contacts, s.net, o);
  CHECK(a == render_svg(s.p, s.contacts, s.net, o));
  CHECK(a.find(">phi = 0.8 &amp; &lt;test&gt;</text>") != std::string::npos);
  CHECK(count(a, "class=\"caption\"") == 2);
  s.net.rattler.pop_back();
  CHECK_THROWS_AS(render_svg(s.p, s.contacts, s.net), std::invalid_argument);
}

TEST_CASE("render_size is the width and height the SVG declares, for any scale, legend and caption") {
  const auto s = make();
  for (const double scale : {1.0, 48.0, 1e4})
    for (const bool legend : {true, false})
      for (const std::string caption : {"", "one line", "two\nlines"}) {
        RenderOptions o;
        o.pixels_per_unit = scale;
        o.legend = legend;
        o.caption = caption;
        const RenderSize size = render_size(s.p.box.L, o);
        const std::string svg = render_svg(s.p, s.contacts, s.net, o);
        const auto attribute = [&](const std::string& name) {
          const auto at = svg.find(name + "=\"", svg.find("<svg "));
          return std::stod(svg.substr(at + name.size() + 2));
        };
        INFO("scale " << scale << ", legend " << legend << ", caption '" << caption << "'");
        CHECK(attribute("width") == Approx(size.width).margin(0.005));  // the SVG has 2 decimals
        CHECK(attribute("height") == Approx(size.height).margin(0.005));
        CHECK(size.width >= scale * s.p.box.L);
        CHECK(size.height >= size.width);  // legend and caption go below the box
      }
}
