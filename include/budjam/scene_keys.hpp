#pragma once
// The knob table: every key of a scene, one row each — where it lives in a Scene, its type, the
// values it accepts and its one-line help. The Scene's member initialisers are the defaults.
// validate() checks each row's range, the scene-file reader (tools/io/scene_file) reads each row by
// its type, `--set` and the writers go through the same rows, and `budjam validate --keys-markdown`
// prints the table of docs/files.md from it. Rules that tie several keys together (the box must hold
// the largest cell, dt_min < dt, ...) stay in validate().
#include "budjam/scene.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace budjam {

// A key's value as a scene file spells it: a choice is its name, growth.P0 = none the string "none".
using SceneValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

enum class KeyType {
  text,          // a one-line, non-empty string (std::string)
  choice,        // one of SceneKey::choices (an enum, in the order of its enumerators)
  flag,          // true or false
  integer,       // an integer in [SceneKey::min_integer, SceneKey::max_integer] (the field's type)
  real,          // a finite number
  real_or_none,  // a finite number, or "none" (std::optional<double>)
  reals,         // a strictly increasing list of finite numbers
};

// The values a number may take: an interval, each end open or closed (infinite: no bound).
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  bool lo_open = false;
  double hi = std::numeric_limits<double>::infinity();
  bool hi_open = false;
  std::string why;  // appended to the requirement, e.g. " so that every γ0 > 0"

  bool contains(double v) const;
  // "must be positive", "must lie in [0, 2) so that every γ0 > 0", ...; "" for no bound.
  std::string requirement() const;
  // "> 0", "[0, 2)", ...; "" for no bound.
  std::string interval() const;
};

struct SceneKey {
  std::string section;  // "run", "box", ..., "observe.moduli"
  std::string name;
  KeyType type = KeyType::real;
  std::string help;                               // one line: meaning and unit
  Range range;                                    // numbers (each element of a list)
  std::vector<std::string> choices;               // KeyType::choice
  std::int64_t min_integer = 0, max_integer = 0;  // KeyType::integer: what the field can hold
  std::function<SceneValue(const Scene&)> get;
  // Stores a value of the row's type (as get() returns it; a choice by one of its names).
  std::function<void(Scene&, const SceneValue&)> set;

  std::string key() const { return section + "." + name; }
  // Throws InputError "<key>: <requirement> (got <value>)" if the scene's value breaks the row.
  void check(const Scene& scene) const;
};

// Every key, grouped by section in file order: run, box, cells, init, growth, jamming, minimiser,
// observe, observe.moduli, observe.dos.
const std::vector<SceneKey>& scene_keys();

// The row of "section.name", or nullptr.
const SceneKey* find_scene_key(std::string_view key);

// The value of one key ("growth.P0") in a scene; InputError "<key>: unknown key".
SceneValue scene_value(const Scene& scene, std::string_view key);

// One value of an enumerated option (a choice key, an export format) and what it means.
struct Choice {
  std::string_view name;
  std::string_view meaning;
};
// `"a" (meaning of a), "b" (...) or "c" (...)`: the values in order, for one-line help texts.
std::string describe_choices(const std::vector<Choice>& choices);

// A value as messages show it: numbers as the shortest text that reads back the same ("0.002"),
// strings in quotes, lists in brackets.
std::string value_text(const SceneValue& value);

// The largest box side: random seed placement keeps a list per bin of about one cell diameter (up
// to L² lists of 24 bytes: 2.4 GB at this bound) and the cell list numbers its cells with 32-bit
// integers (at most L² cells). A box this large never jams within any affordable run anyway
// (about 0.8 L² cells at jamming).
inline constexpr double kMaxBoxSide = 1e4;

// The deepest compression a run may grow to. The smallest r/σ over the contacts of grown packings
// (the demo scene without feedback, docs/model.md) is 0.77 at Δφ = 0.2 and 0.63 at 0.4: beyond 0.4 a
// run would approach the packing rules' bound r > σ/2. Within it a run can still reach the bound
// (small boxes, bisection): it then ends with status overlap_bound instead of writing the packing.
inline constexpr double kMaxDphi = 0.4;

// The largest minimiser.force_tol² over jamming.epsilon_U: a relaxation stopped at |F| < force_tol
// leaves about force_tol²/2k in each contact it did not balance, which must lie well below ε_U.
inline constexpr double kResidualEnergyOverWindow = 0.01;

// The smallest feedback scale growth.P0: p/P0 must stay a finite double for the growth factors
// exp(−p/P0) to keep their order in log scale (an overflow to ∞ made χ_c and the adaptive step NaN);
// with P0 ≥ 10⁻³⁰⁰ it does for every bud pressure below 10⁸, far above any grown packing's.
inline constexpr double kMinP0 = 1e-300;

// The most cells random seed placement may start from: the initial state holds about 0.5 kB per
// cell (peak resident memory of `budjam grow` to its first step: 56 MB at 10⁵ cells, 484 MB at
// 10⁶; docs/files.md), and a run from 10⁶ cells grows far beyond any affordable cost anyway.
inline constexpr double kMaxInitialCells = 1e6;

// Every landed target writes a packing file (and its summary, moduli and spectrum records): the
// targets are bounded in number, and their packings in total size. A packing file holds about
// kPackingBytesPerCell bytes per cell and a packing at jamming about kCellsPerArea L² cells
// (measured on grown packings, docs/files.md), so the targets of a box of side L write about
// targets · kPackingBytesPerCell · kCellsPerArea · L² bytes.
inline constexpr std::size_t kMaxTargets = 1000;
inline constexpr double kPackingBytesPerCell = 110;
inline constexpr double kCellsPerArea = 0.8;
inline constexpr double kMaxTargetOutputBytes = 10e9;

}  // namespace budjam
