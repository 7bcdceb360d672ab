#include "budjam/jamming.hpp"

#include "budjam/scene.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

namespace budjam {

const char* to_string(TrialStart start) {
  switch (start) {
    case TrialStart::accepted_state: return "accepted_state";
    case TrialStart::lowest_overshoot: return "lowest_overshoot";
    case TrialStart::settled: return "settled";
  }
  return "?";
}

const char* to_string(WindowSide side) {
  switch (side) {
    case WindowSide::below: return "below";
    case WindowSide::inside: return "inside";
    case WindowSide::above: return "above";
  }
  return "?";
}

WindowSide JammingWindow::side(double E_per_cell) const {
  if (E_per_cell < bottom_) return WindowSide::below;
  if (E_per_cell <= top()) return WindowSide::inside;
  return WindowSide::above;
}

// The middle in s = √(E/N): ½(√ε_U + √(kTopOverBottom·ε_U)), factored as the searches have always
// computed it (their trials depend on its last bit).
double JammingWindow::s_centre() const { return 0.5 * (1.0 + std::sqrt(kTopOverBottom)) * std::sqrt(bottom_); }
double JammingWindow::s_top() const { return std::sqrt(top()); }

JammingWindow jamming_window(const Scene& scene) { return JammingWindow(scene.epsilon_U); }

JammingOvershoot overshoot_line(double phi, double E_per_cell, std::size_t N, double P, double L) {
  const double s = std::sqrt(E_per_cell), U = E_per_cell * static_cast<double>(N);
  const double dphi = 2.0 * U * phi / (U + L * L * P);
  return {phi, s, dphi > 0 ? s / dphi : 0.0};
}

double dt_for_phi(const PhiAfter& phi_after, double goal, double dt_lo, double dt_hi, double tol) {
  double lo = dt_lo, hi = dt_hi;
  while (true) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) return lo;
    const double miss = phi_after(mid) - goal;
    if (std::abs(miss) <= tol) return mid;
    (miss < 0 ? lo : hi) = mid;
  }
}

namespace {

// Above jamming: the Δt that lands the next target, solved for when the nominal step would pass it.
double target_dt(const SearchFrom& from) {
  if (from.target_phi && from.phi_after(from.dt) > *from.target_phi + from.target_tolerance)
    return dt_for_phi(from.phi_after, *from.target_phi, 0, from.dt, 0.5 * from.target_tolerance);
  return from.dt;
}

NextTrial grow_by(double dt) { return NextTrial{NextTrial::Kind::grow, dt, {}}; }

// Every rejection halves Δt (the driver does it): the searcher only passes the driver's Δt on.
class Bisection final : public JammingSearcher {
 public:
  NextTrial next_trial(const SearchFrom& from) override { return grow_by(from.dt); }
  void accepted(double, bool, bool) override {}
};

// The secant search on s = √(E/N): from the accepted state, aims each trial at the middle of the
// window on the line through the lowest overshoot of this unjammed phase; lands targets above it.
class Secant final : public JammingSearcher {
 public:
  explicit Secant(const JammingWindow& window) : window_(window) {}

  NextTrial next_trial(const SearchFrom& from) override {
    if (!from.unjammed) return grow_by(target_dt(from));
    const std::optional<double> goal = search_goal(from.phi);
    return grow_by(goal ? dt_for_phi(from.phi_after, *goal, 0, from.dt, 1e-3 * s_.bracket_width) : from.dt);
  }

  bool keeps_overshoots() const override { return true; }
  void keep_overshoot(Trial&&, const JammingOvershoot& line) override { s_.overshoots.push_back(line); }

  void accepted(double phi, bool unjammed, bool phase_changed) override {
    if (phase_changed) s_ = {};
    if (unjammed) prune(phi);
  }

  JammingSearchState state() const override { return s_; }
  void restore(JammingSearchState s) override { s_ = std::move(s); }

 private:
  void sort() {
    std::sort(s_.overshoots.begin(), s_.overshoots.end(),
              [](const JammingOvershoot& a, const JammingOvershoot& b) { return a.phi < b.phi; });
  }

  // s = √(E/N) on the line through the lowest overshoot: the secant through the two lowest, or the
  // virial slope of the lowest alone. Requires overshoots sorted by φ, not empty.
  double line_slope() const {
    const std::vector<JammingOvershoot>& o = s_.overshoots;
    if (o.size() >= 2 && o[1].s > o[0].s) return (o[1].s - o[0].s) / (o[1].phi - o[0].phi);
    return o[0].slope;
  }

  // After an unjammed state at φ was accepted: overshoots at or below it are gone, and an overshoot
  // found from an earlier accepted state whose line puts this unjammed state above the jamming
  // window does not hold on this path (φ_J depends on the path): dropped too.
  void prune(double phi) {
    std::vector<JammingOvershoot>& o = s_.overshoots;
    std::erase_if(o, [&](const JammingOvershoot& a) { return a.phi <= phi; });
    sort();
    while (!o.empty() && o[0].s - line_slope() * (o[0].phi - phi) > window_.s_top()) o.erase(o.begin());
  }

  // The φ the next trial aims at: where s reaches the middle of the window on the line through the
  // lowest overshoot, kept strictly inside the bracket (φ, lowest overshoot). Two trials in a row
  // that do not halve the bracket make the next one a bisection, so the search is never slower
  // than halving. nullopt without an overshoot.
  std::optional<double> search_goal(double phi) {
    if (s_.overshoots.empty()) return std::nullopt;
    sort();
    const JammingOvershoot& a = s_.overshoots.front();
    const double width = a.phi - phi;
    s_.slow_trials = (s_.bracket_width > 0 && width > 0.5 * s_.bracket_width) ? s_.slow_trials + 1 : 0;
    s_.bracket_width = width;
    double goal = phi + 0.5 * width;
    const double slope = line_slope();
    if (s_.slow_trials >= 2)
      s_.slow_trials = 0;
    else if (slope > 0)
      goal = a.phi - (a.s - window_.s_centre()) / slope;
    return std::clamp(goal, phi + width / 32, a.phi - width / 32);
  }

  JammingWindow window_;
  JammingSearchState s_;
};

// The bracket search: from the fixed accepted state, φ_J lies between the largest Δt whose trial
// relaxed below the jamming window and the smallest whose trial overshot it. Opened by the first
// overshoot, closed by the next accepted state; a checkpoint between its trials keeps it open.
// Lands targets above jamming.
class BracketSearch final : public JammingSearcher {
 public:
  explicit BracketSearch(const Scene& scene)
      : window_(jamming_window(scene)),
        dt_min_(scene.dt_min),
        jump_factor_(scene.jump_factor),
        start_across_divisions_(scene.start_across_divisions),
        budget_(scene.trial_budget) {}

  NextTrial next_trial(const SearchFrom& from) override {
    if (!from.unjammed) return grow_by(target_dt(from));
    if (!open_) return grow_by(from.dt);
    if (top_to_resume(from.phi)) {
      NextTrial next{NextTrial::Kind::resume, 0, std::move(open_->above.front().trial)};
      open_->above.erase(open_->above.begin());
      return next;
    }
    if (collapsed(from.phi)) {
      NextTrial next{NextTrial::Kind::settle, 0, std::move(*open_->below)};
      open_.reset();
      return next;
    }
    return grow_by(bracket_dt(from));
  }

  // A trial inside the bracket starts from the relaxed positions of the lowest overshoot: they lie
  // next to the jammed configuration. The overshoot's larger step may have divided more cells;
  // those are put back together from their newborns (start_across_divisions; otherwise such a
  // trial starts from the accepted state). Shrunk back towards the accepted state's sizes, an
  // overshoot's configuration may however stay jammed where the accepted state's is not: until a
  // trial has relaxed below the window, an overshoot that was itself started so is not started from
  // again (the next trial starts from the accepted state), so that the bracket always closes.
  void place(Trial& t) const override {
    if (!open_) return;
    const Trial& top = open_->above[0].trial;
    if (!open_->below && top.start == TrialStart::lowest_overshoot) return;
    const auto same = [](const Division& a, const Division& b) { return a.mother_index == b.mother_index; };
    if (!start_across_divisions_ && !std::ranges::equal(t.divisions, top.divisions, same)) return;
    std::optional<Eigen::VectorXd> q = coordinates_before_divisions(top.packing, top.divisions, t.divisions);
    if (!q) return;
    t.packing.q = std::move(*q);
    t.start = TrialStart::lowest_overshoot;
  }

  // The lowest overshoot, relaxed, when the trial starts from it with the same divisions: the same
  // cells, grown further, so the trial's relaxed state is on its branch (continuation.hpp).
  const Packing* branch_start(const Trial& t) const override {
    if (!open_ || t.start != TrialStart::lowest_overshoot) return nullptr;
    const Trial& top = open_->above[0].trial;
    const auto same = [](const Division& a, const Division& b) { return a.mother_index == b.mother_index; };
    if (top.deferred || !std::ranges::equal(t.divisions, top.divisions, same)) return nullptr;
    return &top.packing;
  }

  // Inside an open bracket a trial only has to be placed above or below the window: one that creeps
  // on past the budget far above the window is set aside as a deferred upper end.
  long trial_budget() const override { return open_ ? budget_ : 0; }
  bool classifying() const override { return open_.has_value(); }

  bool keeps_overshoots() const override { return true; }
  // An overshoot (or a deferred trial) is the new upper end of the bracket (trials lie inside it),
  // opening it if needed.
  void keep_overshoot(Trial&& t, const JammingOvershoot& line) override {
    if (!open_) open_ = Bracket{};
    std::vector<End>& above = open_->above;
    above.insert(above.begin(), End{std::move(t), line});
    // The two lowest relaxed overshoots stay, and the deferred trials beneath them: a deferred trial
    // may yet relax below the window, and the bracket then still has its relaxed upper end.
    int relaxed = 0;
    const auto last = std::ranges::find_if(above, [&](const End& e) { return !e.trial.deferred && ++relaxed == 2; });
    if (last != above.end()) above.erase(std::next(last), above.end());
  }
  void keep_below(Trial&& t) override { open_->below = std::move(t); }

  void accepted(double, bool, bool phase_changed) override {
    if (phase_changed) open_.reset();
  }

  JammingSearchState state() const override {
    JammingSearchState s;
    s.bracket = open_;
    return s;
  }
  void restore(JammingSearchState s) override { open_ = std::move(s.bracket); }

 private:
  using End = BracketEnd;
  using Bracket = OpenBracket;

  double dt_lo() const { return open_->below ? open_->below->dt : 0.0; }
  double phi_lo(double phi) const { return open_->below ? open_->below->packing.packing_fraction() : phi; }

  // ds/dφ of the line through the lowest overshoot: the secant through the two lowest (same base,
  // so the same function s(Δt)), or the virial slope of the lowest alone (also when either is a
  // deferred trial, whose s is only an upper bound).
  double slope() const {
    const std::vector<End>& above = open_->above;
    const JammingOvershoot& a = above[0].line;
    const bool relaxed = above.size() >= 2 && !above[0].trial.deferred && !above[1].trial.deferred;
    if (relaxed && above[1].line.s > a.s && above[1].line.phi > a.phi)
      return (above[1].line.s - a.s) / (above[1].line.phi - a.phi);
    return a.slope;
  }

  // Δt of the next trial in the bracket: where the line through the lowest overshoot reaches the
  // middle of the window (φ(Δt) solved for between the ends), at least 1/32 of the bracket from
  // either end; after two trials that did not halve the bracket, its middle.
  double bracket_dt(const SearchFrom& from) {
    Bracket& b = *open_;
    const JammingOvershoot& a = b.above[0].line;
    const double lo = dt_lo(), hi = b.above[0].trial.dt, width = hi - lo;
    b.slow_trials = (b.width > 0 && width > 0.5 * b.width) ? b.slow_trials + 1 : 0;
    b.width = width;
    double step = lo + 0.5 * width;
    const double k = slope();
    if (b.slow_trials >= 2) {
      b.slow_trials = 0;
    } else if (k > 0) {
      const double goal = a.phi - (a.s - window_.s_centre()) / k, low = phi_lo(from.phi);
      if (goal > low && goal < a.phi) step = dt_for_phi(from.phi_after, goal, lo, hi, 1e-3 * (a.phi - low));
    }
    return std::clamp(step, lo + width / 32, hi - width / 32);
  }

  // Whether no trial can land in the window: the bracket, from a trial below it, has shrunk to an
  // eighth of the distance the line puts between its upper end and the middle of the window (or
  // below growth.dt_min), so s jumps across the window (a division, or the relaxation falling into
  // another basin); or s visibly jumps at the lower end (jumps_at_lower_end). Without a trial
  // below, the search goes on (to dt_underflow at worst).
  bool collapsed(double phi) const {
    if (!open_->below) return false;
    if (open_->above.empty()) return true;  // its only upper end, resumed, relaxed below the window
    const JammingOvershoot& a = open_->above[0].line;
    const double k = slope();
    const double reach = k > 0 ? (a.s - window_.s_centre()) / k : 0.0;
    return a.phi - phi_lo(phi) < reach / 8 || open_->above[0].trial.dt - dt_lo() < dt_min_ || jumps_at_lower_end(phi);
  }

  // Overshoots relaxed from the lowest one form one branch of minima, on which s = √(E/N) is nearly
  // linear in φ. When the two lowest lie on it close to the lower end (the farther at most
  // kNearLowerEnd times as far from it as the nearer, so the line is a local one) and their line
  // meets the lower end far above the window, the branch does not come down to the window before
  // the lower end: s jumps there. Without this test the bracket would halve towards the lower end
  // with overshoots whose E/N levels off above the window, each a marginal relaxation, until its
  // width decides (docs/jamming.md).
  bool jumps_at_lower_end(double phi) const {
    constexpr double kNearLowerEnd = 4.0;
    const std::vector<End>& above = open_->above;
    if (jump_factor_ <= 0 || above.size() < 2) return false;
    if (above[0].trial.start != TrialStart::lowest_overshoot || above[1].trial.start != TrialStart::lowest_overshoot)
      return false;
    if (above[0].trial.deferred || above[1].trial.deferred) return false;  // their E/N is still falling
    const JammingOvershoot &a = above[0].line, &b = above[1].line;
    const double lo = phi_lo(phi);
    if (!(b.phi > a.phi && a.phi > lo) || b.phi - lo > kNearLowerEnd * (a.phi - lo)) return false;
    const double s_at_lo = a.s - (b.s - a.s) / (b.phi - a.phi) * (a.phi - lo);
    return s_at_lo > jump_factor_ * window_.s_top();
  }

  // A deferred upper end is worth its remaining relaxation only once the bracket has collapsed onto
  // it: trials beneath it are cheap (they relax below the window, or overshoot it and make it moot,
  // or land in it), its remaining creep is not.
  bool top_to_resume(double phi) const {
    return !open_->above.empty() && open_->above.front().trial.deferred && collapsed(phi);
  }

  JammingWindow window_;
  double dt_min_, jump_factor_;
  bool start_across_divisions_;
  long budget_;
  std::optional<Bracket> open_;
};

}  // namespace

const std::vector<JammingSearchKind>& jamming_searches() {
  static const std::vector<JammingSearchKind> searches = {
      {JammingSearch::bisection, "bisection", "the paper's protocol: every overshoot halves Δt",
       [](const Scene&) -> std::unique_ptr<JammingSearcher> { return std::make_unique<Bisection>(); }},
      {JammingSearch::secant, "secant",
       "each trial aimed at the window's middle by a secant in √(E/N), from each accepted state",
       [](const Scene& scene) -> std::unique_ptr<JammingSearcher> {
         return std::make_unique<Secant>(jamming_window(scene));
       }},
      {JammingSearch::bracket, "bracket", "the secant's aim, with φ_J bracketed in Δt from one fixed accepted state",
       [](const Scene& scene) -> std::unique_ptr<JammingSearcher> { return std::make_unique<BracketSearch>(scene); }},
  };
  return searches;
}

std::unique_ptr<JammingSearcher> make_jamming_searcher(const Scene& scene) {
  return jamming_searches().at(static_cast<std::size_t>(scene.search)).make(scene);
}

}  // namespace budjam
