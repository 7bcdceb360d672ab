// `budjam render PACKING -o FILE.svg [--png] [--scale PX] [--no-images] [--no-contacts]`
// Draws a packing file as SVG (budjam/render.hpp): lobes with their periodic images, contacts
// coloured by force, rattlers greyed, unconstrained buds marked. --png also converts it with
// Debian's rsvg-convert (package librsvg2-bin) to FILE.png.
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include "budjam/render.hpp"
#include "budjam/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/packing_file.hpp"

#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace budjam;

struct Options {
  std::string packing;
  std::string out;
  bool png = false;
  double scale = 48.0;
  bool no_images = false;
  bool no_contacts = false;
};

// Runs a program with arguments (no shell); returns its exit status, or throws IoError if it
// cannot be started.
int run_program(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ);
  if (rc != 0)
    throw io::IoError("render --png: cannot run " + argv[0] + ": " + std::strerror(rc) +
                      " (install Debian's librsvg2-bin)");
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw io::IoError("render --png: waitpid failed");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

void run(const Options& o) {
  if (!(o.scale > 0)) throw InputError("--scale: must be positive (got " + std::to_string(o.scale) + ")");
  fs::path out = o.out;
  if (out.extension() != ".svg") throw InputError("-o: the output must end in .svg (got " + o.out + ")");
  const io::PackingFile f = io::read_packing(o.packing);
  const tools::PackingContacts pc = tools::analyse_contacts(f.packing);

  RenderOptions ro;
  ro.pixels_per_unit = o.scale;
  ro.periodic_images = !o.no_images;
  ro.draw_contacts = !o.no_contacts;
  char buf[256];
  const auto& m = f.meta;
  std::snprintf(buf, sizeof buf, "%s: N = %zu, L = %g, phi = %.6f, P = %.3g\nZ = %.3f, rattlers = %zu, unconstrained buds = %zu",
                m.get("kind").value_or(fs::path(o.packing).stem().string()).c_str(), f.packing.size(), f.packing.box.L,
                f.packing.packing_fraction(), pc.P, pc.network.Z, pc.network.N_f, pc.network.N_u_buds);
  ro.caption = buf;
  io::write_atomically(out, render_svg(f.packing, pc.contacts, pc.network, ro));

  if (o.png) {
    fs::path png = out;
    png.replace_extension(".png");
    fs::path tmp = png;
    tmp += ".tmp";
    // "--output=" and "--": a file name that starts with "-" is a file, not an option.
    const int rc = run_program({"rsvg-convert", "--output=" + tmp.string(), "--", out.string()});
    if (rc != 0) {
      fs::remove(tmp);
      throw io::IoError("render --png: rsvg-convert failed with status " + std::to_string(rc));
    }
    fs::rename(tmp, png);
  }
}

const bool registered = budjam::cli::register_command(
    {"render", "Draw a packing file as SVG (and PNG): cells, contacts by force, rattlers, free buds",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack)")->required();
       sub.add_option("-o,--out", o->out, "output SVG file")->required()->type_name("FILE.svg");
       sub.add_flag("--png", o->png, "also write FILE.png (rsvg-convert)");
       sub.add_option("--scale", o->scale, "pixels per mother diameter (default 48)");
       sub.add_flag("--no-images", o->no_images, "do not draw periodic images across the boundary");
       sub.add_flag("--no-contacts", o->no_contacts, "do not draw contacts");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
