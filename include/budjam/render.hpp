#pragma once
// A picture of a packing as SVG text: every cell as its mother and bud lobes, drawn with their
// periodic images where they cross the box boundary (and clipped to the box), a dark bar from each
// mother's centre to its bud's (class "link"), the contacts as segments between lobe centres
// coloured by force, rattlers greyed and unconstrained buds marked.
// Returns the document as a string; writing it (and converting it to PNG) is the caller's business.
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"

namespace budjam {

struct RenderOptions {
  double pixels_per_unit = 48.0;  // one mother diameter D0 = 1 in pixels
  double margin = 0.25;           // around the box, in units of D0
  bool periodic_images = true;    // draw the copies of lobes/contacts that cross the boundary
  bool draw_contacts = true;
  bool legend = true;   // force scale and the meaning of the marks, below the box
  std::string caption;  // text under the picture; "\n" separates lines
};

// Colour of a contact with force f on the scale [0, f_max]: a perceptually ordered ramp from pale
// yellow (weak) to dark red (strongest), as "#rrggbb". f ≤ 0 gives the weakest colour.
std::string force_colour(double f, double f_max);

// The picture's width and height in pixels for a box of side L.
struct RenderSize {
  double width, height;
};
RenderSize render_size(double L, const RenderOptions& options);

// `contacts` and `net` are those of `packing` (find_contacts + analyse_network); contacts that
// involve a rattler are drawn thin and grey. Throws std::invalid_argument if the network does not
// belong to the packing (cell counts differ) or a contact names a lobe that does not exist.
std::string render_svg(const Packing& packing, const std::vector<Contact>& contacts, const ContactNetwork& net,
                       const RenderOptions& options = {});

}  // namespace budjam
