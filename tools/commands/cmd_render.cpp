// `budjam render PACKING -o FILE.svg|FILE.png|FILE.pdf [--png] [--scale PX] [--no-images] [--no-contacts]`
// Draws a packing file as SVG (budjam/render.hpp): lobes with their periodic images, each bud
// linked to its mother by a dark bar, contacts coloured by force, rattlers greyed, unconstrained
// buds marked. A .png or .pdf output is
// converted from the SVG by Debian's rsvg-convert (package librsvg2-bin); --png also writes
// FILE.png beside FILE.svg.
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include "budjam/errors.hpp"
#include "budjam/render.hpp"
#include "io/atomic_file.hpp"
#include "io/packing_file.hpp"
#include "io/result_files.hpp"

#include "io/run_program.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace budjam::cli::render_command {
namespace {

namespace fs = std::filesystem;

struct Options {
  std::string packing;
  std::string out;
  bool png = false;
  double scale = 48.0;
  bool no_images = false;
  bool no_contacts = false;
};

// The largest side of a PNG or PDF that rsvg-convert (cairo) draws, and of an SVG (a picture no
// viewer opens is no output).
constexpr long kMaxConvertedPixels = 32767, kMaxSvgPixels = 1000000;

// rsvg-convert SVG -> PNG/PDF into `tmp`, which the caller commits: the output is complete or untouched.
void convert_svg(const fs::path& svg, const io::TempFile& tmp, const std::string& format) {
  // On standard output, into the temporary's descriptor: rsvg-convert given a name writes a
  // temporary of its own beside it, which a signal would leave behind. "--": a file name that
  // starts with "-" is a file, not an option.
  const io::ProgramResult r = io::run_program({"rsvg-convert", "-f", format, "--", svg.string()}, "render",
                                              "install Debian's librsvg2-bin", tmp.fd());
  if (!r.ok())
    throw io::IoError("render: " + io::one_line(tmp.final_path().string()) + ": rsvg-convert " + r.failure());
}

void run(const Options& o) {
  if (!(std::isfinite(o.scale) && o.scale > 0))
    throw InputError("--scale: must be a positive number (got " + std::to_string(o.scale) + ")");
  const fs::path out = o.out;
  io::check_output_name("-o", out);
  const std::string ext = out.extension().string();
  const std::string name = out.filename().string();
  if (name == ".svg" || name == ".png" || name == ".pdf")  // std::filesystem: a stem, no extension
    throw InputError("-o: " + io::escape_control(o.out) + ": no file name before the extension " + name);
  if (ext != ".svg" && ext != ".png" && ext != ".pdf")
    throw InputError("-o: the output must end in .svg, .png or .pdf (got " + io::escape_control(o.out) + ")");
  if (o.png) io::check_output_name("--png", fs::path(out).replace_extension(".png"));
  io::check_not_an_input("-o", out, {o.packing});
  if (o.png) io::check_not_an_input("--png", fs::path(out).replace_extension(".png"), {o.packing});
  const io::PackingFile f = io::read_packing(o.packing);
  const tools::PackingContacts pc = tools::analyse_contacts(f.packing);

  RenderOptions ro;
  ro.pixels_per_unit = o.scale;
  ro.periodic_images = !o.no_images;
  ro.draw_contacts = !o.no_contacts;
  char buf[256];
  const auto& m = f.meta;
  std::snprintf(buf, sizeof buf,
                "%s: N = %zu, L = %g, phi = %.6f, P = %.3g\nZ = %.3f, rattlers = %zu, unconstrained buds = %zu",
                m.get("kind").value_or(fs::path(o.packing).stem().string()).c_str(), f.packing.size(), f.packing.box.L,
                f.packing.packing_fraction(), pc.P, pc.network.Z, pc.network.N_f, pc.network.N_u_buds);
  ro.caption = buf;
  {
    const RenderSize size = render_size(f.packing.box.L, ro);
    // Pixel counts as text without converting to an integer type (a huge --scale overflows any).
    const auto pixels = [](double v) {
      char text[64];
      std::snprintf(text, sizeof text, "%.0f", std::round(v));
      return std::string(text);
    };
    const double largest = std::max(size.width, size.height), smallest = std::min(size.width, size.height);
    const std::string picture_size =
        "--scale: the picture would be " +
        (largest < 1e15 ? pixels(size.width) + " × " + pixels(size.height) : std::string("more than 10^15 a side in")) +
        " pixels";
    const bool converted = ext != ".svg" || o.png;
    if (!(largest <= (converted ? kMaxConvertedPixels : kMaxSvgPixels)))
      throw InputError(picture_size + ", and " +
                       (converted
                            ? "rsvg-convert draws at most " + std::to_string(kMaxConvertedPixels) +
                                  " a side: lower --scale, or write an SVG"
                            : "an SVG is drawn at most " + std::to_string(kMaxSvgPixels) + " a side: lower --scale"));
    if (!(smallest >= 1)) throw InputError(picture_size + ", less than one a side: raise --scale");
  }
  const io::Directory dir = io::Directory::open(out.parent_path(), true);
  const std::string picture = render_svg(f.packing, pc.contacts, pc.network, ro);
  io::TempFile svg(dir, name);
  svg.write(picture);
  if (ext != ".svg") {  // only the converted file is an output: the SVG is never committed
    io::TempFile converted(dir, name);
    convert_svg(svg.path(), converted, ext.substr(1));
    converted.commit();
    return;
  }
  if (!o.png) return svg.commit();
  // Both files or neither: the PNG is made before either replaces its predecessor.
  io::TempFile png(dir, fs::path(name).replace_extension(".png").string());
  convert_svg(svg.path(), png, "png");
  const io::SignalsHeld held;  // no stop between the two renames
  svg.commit();
  png.commit();
}

const bool registered = budjam::cli::register_command(
    {"render", "Draw a packing file as SVG, PNG or PDF: cells, contacts by force, rattlers, free buds",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack)")->required();
       sub.add_option("-o,--out", o->out, "output file: SVG, or PNG/PDF converted by rsvg-convert")
           ->required()
           ->check(budjam::cli::names_a_path())
           ->type_name("FILE.svg|.png|.pdf");
       sub.add_flag("--png", o->png, "with an SVG output, also write FILE.png beside it (rsvg-convert)");
       sub.add_option("--scale", o->scale, "pixels per mother diameter (default 48)");
       sub.add_flag("--no-images", o->no_images, "do not draw periodic images across the boundary");
       sub.add_flag("--no-contacts", o->no_contacts, "do not draw contacts");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::render_command
