// `budjam validate FILE`: checks a scene (or a packing file) and prints what budjam would use.
// For a scene: the effective scene, every key, as TOML (or JSON), after any --set overrides.
// For a packing: its header, metadata and packing fraction. --keys-markdown prints the table of
// scene keys (the one in docs/files.md) instead, --observers-markdown the table of observers (the
// one in docs/growth.md).
#include "commands/command.hpp"

#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "io/scene_file.hpp"
#include "observers/observers.hpp"

#include <iostream>
#include <memory>

namespace budjam::cli::validate_command {
namespace {

struct Options {
  std::string file;
  std::vector<std::string> overrides;
  bool json = false;
  bool comments = false;
  bool keys_markdown = false;
  bool observers_markdown = false;
};

void show_packing(const Options& o, const std::string& text) {
  using budjam::io::Json;
  if (!o.overrides.empty()) throw budjam::InputError("--set applies to scenes, and " + o.file + " is a packing file");
  const auto f = budjam::io::parse_packing(text, o.file);
  const auto& p = f.packing;
  Json j;
  j["format"] = "budjam-packing";
  j["version"] = budjam::io::kPackingFormatVersion;
  j["N"] = p.size();
  j["L"] = p.box.L;
  j["shear"] = p.box.shear;
  j["next_id"] = p.next_id;
  j["phi"] = p.packing_fraction();
  j["meta"] = Json::object();
  for (const auto& [k, v] : f.meta.values) j["meta"][k] = v;
  if (o.json) {
    std::cout << budjam::io::json_text(j);
    return;
  }
  std::cout << "# " << o.file << ": a valid budjam packing file\n";
  for (const auto& [k, v] : j.items()) {
    if (k == "meta") continue;
    std::cout << k << " = " << (v.is_string() ? v.get<std::string>() : v.dump()) << "\n";
  }
  for (const auto& [k, v] : f.meta.values) std::cout << "meta." << k << " = " << v << "\n";
}

void run(const Options& o) {
  if (o.keys_markdown) {
    std::cout << budjam::io::scene_keys_markdown();
    return;
  }
  if (o.observers_markdown) {
    std::cout << budjam::tools::observers_markdown();
    return;
  }
  if (o.file.empty()) throw budjam::InputError("FILE: a scene or packing file is required");
  const std::string text = budjam::io::read_text_file(o.file);
  if (budjam::io::looks_like_packing(text)) return show_packing(o, text);
  const budjam::Scene scene = budjam::io::parse_scene(text, o.file, o.overrides);
  if (o.json)
    std::cout << budjam::io::json_text(budjam::io::scene_to_json(scene));
  else
    std::cout << budjam::io::scene_to_toml(scene, o.comments);
}

const bool registered = budjam::cli::register_command(
    {"validate", "Check a scene or packing file and print the effective values", [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       auto* file = sub.add_option("FILE", o->file, "scene (.toml) or packing (.pack) file");
       sub.add_option("--set", o->overrides, "override a scene key, e.g. --set growth.P0=1e-4 (repeatable)")
           ->type_name("KEY=VALUE");
       sub.add_flag("--json", o->json, "print JSON instead of TOML");
       sub.add_flag("--comments", o->comments, "explain every key in the printed TOML");
       sub.add_flag("--keys-markdown", o->keys_markdown,
                    "print every scene key (type, default, range, meaning) as a Markdown table")
           ->excludes(file);
       sub.add_flag("--observers-markdown", o->observers_markdown,
                    "print every observer of a growth run (the keys that switch it on, the files it writes) as a "
                    "Markdown table")
           ->excludes(file);
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::validate_command
