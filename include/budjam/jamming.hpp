#pragma once
// The jamming criterion and the searches onto it (docs/growth.md, "Protocol", and docs/jamming.md).
//
// JammingWindow is the criterion: where a relaxed E/N lies against the window [ε_U, 2ε_U]. Every
// comparison of an energy with ε_U goes through JammingWindow::side(); the quantities the searches
// aim with (√(E/N) at the middle and at the top of the window) are derived from the same edges.
//
// JammingSearcher is the search onto φ_J (and the landing on targets above it) behind one
// interface: the growth driver asks it for the next attempt, hands it the trials that overshot the
// window or fell below it, and tells it of every accepted state. The driver keeps the protocol:
// growing, relaxing, classifying, accepting and the events. A search's state between accepted
// states is JammingSearchState, which a checkpoint stores.
#include "budjam/growth.hpp"
#include "budjam/packing.hpp"
#include "budjam/scene.hpp"

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace budjam {

struct Scene;

// Where a relaxed E/N lies against the jamming window.
enum class WindowSide {
  below,   // E/N < ε_U: unjammed
  inside,  // ε_U ≤ E/N ≤ 2ε_U: a jamming point, if it is a minimum
  above,   // E/N > 2ε_U (or not a number): past the jamming point
};
const char* to_string(WindowSide side);

class JammingWindow {
 public:
  explicit JammingWindow(double epsilon_U) : bottom_(epsilon_U) {}

  // The one test of the criterion.
  WindowSide side(double E_per_cell) const;
  // At or above the window: a jammed state (above jamming, overshooting the window is allowed).
  bool jammed(double E_per_cell) const { return side(E_per_cell) != WindowSide::below; }
  // Inside the window: a jamming candidate, checked for being a saddle before it is taken.
  bool candidate(double E_per_cell) const { return side(E_per_cell) == WindowSide::inside; }
  // A relaxation may stop once E/N falls below this: the energy only falls, so the state is
  // certainly below the window.
  double floor() const { return bottom_; }
  // A relaxation stopped by its iteration budget with E/N at most this close above the window is
  // finished rather than set aside (deferred): it may be the jamming point.
  bool near(double E_per_cell) const { return E_per_cell <= kDeferAbove * top(); }

  // √(E/N) at the middle of the window (between √ε_U and √(2ε_U)), where the searches aim, and at
  // its top.
  double s_centre() const;
  double s_top() const;

 private:
  static constexpr double kTopOverBottom = 2.0;  // the window is [ε_U, 2ε_U]
  static constexpr double kDeferAbove = 100.0;   // times the top of the window (near)
  double top() const { return kTopOverBottom * bottom_; }
  double bottom_;
};

// The window of a scene (jamming.epsilon_U): the driver's and the searches' alike, and the one place
// that reads the criterion's scene keys.
JammingWindow jamming_window(const Scene& scene);

// Where a trial's relaxation started: the accepted state grown by Δt, the relaxed positions of the
// bracket's lowest overshoot with the trial's sizes, or (a collapsed bracket's settle) the highest
// trial below the window, relaxed on.
enum class TrialStart { accepted_state, lowest_overshoot, settled };
const char* to_string(TrialStart start);

// A growth trial from the accepted state, made on copies: a rejection leaves the accepted packing
// and random stream untouched.
struct Trial {
  Packing packing;
  Rng rng;
  std::vector<Division> divisions;
  double dt = 0;  // scaled, as the driver stores steps
  double E = 0;   // E/N after its relaxation
  TrialStart start = TrialStart::accepted_state;
  // Its relaxation spent jamming.trial_budget far above the window: an upper end of the bracket
  // until the bracket collapses onto it; then it is relaxed on.
  bool deferred = false;
};

// A relaxed trial above the jamming window: its φ, s = √(E/N), and the slope ds/dφ it implies.
struct JammingOvershoot {
  double phi = 0, s = 0, slope = 0;
};

// The overshoot line of a relaxed trial at φ with E/N, N cells, pressure P in a box of side L. The
// slope comes from its energy and pressure alone: near φ_J, U ≈ C (φ − φ_J)², so φ − φ_J =
// 2U / (dU/dφ); growing every length by λ at fixed centroids is dU/dλ = 2U + Σ f r = 2U + 2L²P and
// dφ/dλ = 2φ, so dU/dφ ≈ (U + L²P)/φ. Buds grow alone and at different rates, so this is an
// estimate; a second overshoot replaces it by a secant.
JammingOvershoot overshoot_line(double phi, double E_per_cell, std::size_t N, double P, double L);

// An upper end of the bracket search: a relaxed (or deferred) trial above the window and its line.
struct BracketEnd {
  Trial trial;
  JammingOvershoot line;  // its (φ, s = √(E/N), slope)
};

// The bracket around φ_J in Δt from one fixed accepted state, while it is open: from the first
// overshoot to the next accepted state.
struct OpenBracket {
  std::optional<Trial> below;     // the highest trial below the window, relaxed only to E/N < ε_U
  std::vector<BracketEnd> above;  // the two relaxed overshoots of smallest Δt and the deferred trials
                                  // beneath them, smallest Δt first
  int slow_trials = 0;            // consecutive trials that did not halve the bracket
  double width = 0;               // Δt width of the bracket at the last trial
};

// What a search carries between growth attempts, which a checkpoint stores: the secant search's
// overshoots from one accepted state to the next, and the bracket search's open bracket (its kept
// trials), so that a run interrupted inside a search resumes it where it was. Bisection keeps
// nothing (the driver's Δt is halved).
struct JammingSearchState {
  std::vector<JammingOvershoot> overshoots;  // secant: sorted by φ
  int slow_trials = 0;                       // secant: consecutive trials that did not halve the bracket around φ_J
  double bracket_width = 0;            // secant: φ from the accepted state to the lowest overshoot at the last trial
  std::optional<OpenBracket> bracket;  // bracket search, while open
};

// φ after growing the accepted state by a (scaled) Δt, divisions and their draws included: known
// before relaxing, since relaxation moves cells but does not change their areas.
using PhiAfter = std::function<double(double)>;

// A Δt in (dt_lo, dt_hi] with |φ(Δt) − goal| ≤ tol, by bisection from φ(dt_lo) < goal < φ(dt_hi).
// φ rises continuously with Δt except at divisions, where it drops, so the bracket always closes
// on a continuous crossing. Returns the lower end if the bracket shrinks to nothing first.
double dt_for_phi(const PhiAfter& phi_after, double goal, double dt_lo, double dt_hi, double tol);

// The accepted state a search plans the next attempt from.
struct SearchFrom {
  bool unjammed = true;              // the phase: the search onto φ_J, or the landing on targets
  double phi = 0;                    // φ of the accepted state
  double dt = 0;                     // the driver's Δt for the next attempt (nominal, or halved)
  std::optional<double> target_phi;  // above jamming: φ of the next target to land ...
  double target_tolerance = 0;       // ... and how close
  PhiAfter phi_after;
};

// The next attempt: a trial grown from the accepted state by dt, or a kept trial relaxed on (the
// bracket's deferred upper end, resumed; or its highest trial below the window, settled).
struct NextTrial {
  enum class Kind { grow, resume, settle };
  Kind kind = Kind::grow;
  double dt = 0;  // grow: scaled Δt
  Trial trial;    // resume, settle
};

class JammingSearcher {
 public:
  virtual ~JammingSearcher() = default;

  virtual NextTrial next_trial(const SearchFrom& from) = 0;
  // A trial grown by next_trial's dt, before it is relaxed: the search may move its start.
  virtual void place(Trial&) const {}
  // The relaxed state a trial placed by place() lies on the branch of (the same cells at other bud
  // sizes), from which its relaxed state can be followed by continuation; null if none.
  virtual const Packing* branch_start(const Trial&) const { return nullptr; }
  // FIRE iterations a trial may spend before it is deferred; 0 = relaxed to convergence.
  virtual long trial_budget() const { return 0; }
  // Whether trials are only placed above or below the window (an open bracket): their relaxation
  // may stop below the window, and one below it is kept (keep_below) instead of accepted.
  virtual bool classifying() const { return false; }

  // Whether overshoots of the window below jamming are kept (keep_overshoot); if not, the driver
  // halves Δt.
  virtual bool keeps_overshoots() const { return false; }
  virtual void keep_overshoot(Trial&&, const JammingOvershoot&) {}
  // A trial below the window while classifying.
  virtual void keep_below(Trial&&) {}

  // A trial was accepted: φ of the new accepted state, its phase, and whether the phase changed.
  virtual void accepted(double phi, bool unjammed, bool phase_changed) = 0;

  virtual JammingSearchState state() const { return {}; }
  virtual void restore(JammingSearchState) {}
};

// One row per jamming search, in the order of JammingSearch's enumerators: the name a scene gives it
// (`jamming.search`), what it does in one line (the key's help and the table of docs/jamming.md), and how it is made
// from the scene. Adding a search is an enumerator of JammingSearch, a JammingSearcher in jamming.cpp and its row here.
struct JammingSearchKind {
  JammingSearch search;
  std::string_view name;
  std::string_view description;
  std::unique_ptr<JammingSearcher> (*make)(const Scene&);
};
const std::vector<JammingSearchKind>& jamming_searches();

// The search scene.search names, with the scene's window and knobs.
std::unique_ptr<JammingSearcher> make_jamming_searcher(const Scene& scene);

}  // namespace budjam
