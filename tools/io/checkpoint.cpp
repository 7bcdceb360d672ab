#include "io/checkpoint.hpp"

#include "budjam/blas_threads.hpp"
#include "budjam/growth.hpp"
#include "budjam/packing_rules.hpp"
#include "io/atomic_file.hpp"
#include "io/packing_file.hpp"
#include "io/run_data.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <unordered_set>

namespace budjam::io {

namespace {

// Exact text of a double (17 significant digits read back bit-identically).
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

constexpr std::string_view kCheckpointMagic = "budjam-checkpoint";
constexpr std::string_view kChecksum = "checksum ";

// ---- reading: one line at a time, every problem named by file and line --------------------------

class CheckpointText {
 public:
  CheckpointText(std::string_view text, std::string file) : file_(std::move(file)) {
    while (!text.empty()) {
      const std::size_t end = text.find('\n');
      if (end == std::string_view::npos) fail_at(lines_.size() + 1, "the last line does not end with a newline");
      lines_.push_back(text.substr(0, end));
      text.remove_prefix(end + 1);
    }
  }
  [[noreturn]] void fail_at(std::size_t line, const std::string& what) const {
    throw InputError(escape_control(file_ + ":" + std::to_string(line) + ": " + what));
  }
  [[noreturn]] void fail(const std::string& what) const { fail_at(at_, what); }
  std::size_t line() const { return at_; }
  std::size_t count() const { return lines_.size(); }
  std::string_view raw(std::size_t line) const { return lines_[line - 1]; }
  // The next line as it is.
  std::string_view take() {
    if (at_ >= lines_.size()) fail_at(lines_.size(), "truncated");
    return lines_[at_++];
  }

  // The next line as words separated by single spaces; `key` (if not empty) must be its first
  // word and is dropped; exactly `n` words must follow (n < 0: any number).
  std::vector<std::string_view> next(std::string_view key, long n) {
    if (at_ >= lines_.size()) fail_at(lines_.size(), "truncated: expected a line '" + std::string(key) + " ...'");
    const std::string_view l = lines_[at_++];
    std::vector<std::string_view> w;
    std::size_t start = 0;
    while (true) {
      const std::size_t sp = l.find(' ', start);
      w.push_back(l.substr(start, sp == std::string_view::npos ? std::string_view::npos : sp - start));
      if (w.back().empty()) fail("empty field (fields are separated by one space)");
      if (sp == std::string_view::npos) break;
      start = sp + 1;
    }
    if (!key.empty()) {
      if (w.front() != key) fail("expected '" + std::string(key) + "', found '" + std::string(w.front()) + "'");
      w.erase(w.begin());
    }
    if (n >= 0 && static_cast<long>(w.size()) != n)
      fail("expected " + std::to_string(n) + " values" + (key.empty() ? "" : " after '" + std::string(key) + "'") +
           ", found " + std::to_string(w.size()));
    return w;
  }

  double real(std::string_view w, const char* what) const {
    const auto v = parse_double(w);
    if (!v || !std::isfinite(*v)) fail(std::string(what) + ": not a finite number (got '" + std::string(w) + "')");
    return *v;
  }
  double positive(std::string_view w, const char* what) const {
    const double v = real(w, what);
    if (!(v > 0)) fail(std::string(what) + ": must be positive (got '" + std::string(w) + "')");
    return v;
  }
  std::int64_t integer(std::string_view w, const char* what, std::int64_t lo, std::int64_t hi) const {
    const auto v = parse_int64(w);
    if (!v) fail(std::string(what) + ": not an integer (got '" + std::string(w) + "')");
    if (*v < lo || *v > hi)
      fail(std::string(what) + ": " + std::to_string(*v) + " is outside [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "]");
    return *v;
  }
  std::size_t count_of(std::string_view w, const char* what, std::size_t hi) const {
    return static_cast<std::size_t>(integer(w, what, 0, static_cast<std::int64_t>(hi)));
  }
  bool flag(std::string_view w, const char* what) const { return integer(w, what, 0, 1) == 1; }

 private:
  std::string file_;
  std::vector<std::string_view> lines_;
  std::size_t at_ = 0;
};

constexpr std::int64_t kLongMax = std::numeric_limits<long>::max();

// No state of a run holds more cells than a packing fraction of 4 allows (jamming is near 0.85,
// and overlaps stay small): each cell covers at least a mother disk, π D²/4.
std::size_t max_cells(const Scene& scene) {
  return static_cast<std::size_t>(4.0 * scene.L * scene.L /
                                  (0.25 * std::numbers::pi * kMotherDiameter * kMotherDiameter)) +
         scene.n_seeds + 2;
}

struct Section {
  std::string name;
  std::size_t line = 0;  // of its "observer" line
  std::string body;
};

// The contact-network summary of a record (jamming point, target, φ_2): its numbers in the order
// NetworkSummary declares them.
constexpr std::size_t kNetworkWords = 12;

std::string network_text(const NetworkSummary& n) {
  std::ostringstream os;
  os << n.N << ' ' << n.N_nr << ' ' << n.N_f << ' ' << n.N_f_single_pass << ' ' << n.N_c << ' ' << n.N_u << ' '
     << n.N_u_buds << ' ' << num(n.Z) << ' ' << num(n.u) << ' ' << num(n.u_buds) << ' ' << num(n.Z_iso) << ' '
     << num(n.dZ);
  return os.str();
}

// The summary from the words w[at], ..., w[at + kNetworkWords − 1]; counts are bounded by the cells
// (N by `cells_cap`), lobes (2N) and ordered contact pairs (4N²).
NetworkSummary read_network(const CheckpointText& in, const std::vector<std::string_view>& w, std::size_t at,
                            std::size_t cells_cap) {
  NetworkSummary n;
  n.N = in.count_of(w[at], "N", cells_cap);
  n.N_nr = in.count_of(w[at + 1], "N_nr", n.N), n.N_f = in.count_of(w[at + 2], "N_f", n.N);
  n.N_f_single_pass = in.count_of(w[at + 3], "N_f_single", n.N), n.N_c = in.count_of(w[at + 4], "N_c", 4 * n.N * n.N);
  n.N_u = in.count_of(w[at + 5], "N_u", 2 * n.N), n.N_u_buds = in.count_of(w[at + 6], "N_u_buds", n.N);
  n.Z = in.real(w[at + 7], "Z"), n.u = in.real(w[at + 8], "u"), n.u_buds = in.real(w[at + 9], "u_buds");
  n.Z_iso = in.real(w[at + 10], "Z_iso"), n.dZ = in.real(w[at + 11], "dZ");
  return n;
}

// One line per cell: x y θ b γ0 id parent.
void write_cells(std::ostream& os, const Packing& p) {
  for (std::size_t i = 0; i < p.size(); ++i)
    os << num(p.x(i)) << ' ' << num(p.y(i)) << ' ' << num(p.theta(i)) << ' ' << num(p.b[i]) << ' ' << num(p.gamma0[i])
       << ' ' << p.id[i] << ' ' << p.parent[i] << '\n';
}

// A trial kept by an open bracket: its header (an upper end with its overshoot line), its random
// stream, its divisions and its cells. The box is the accepted packing's.
void write_trial(std::ostream& os, std::string_view end, const Trial& t, const JammingOvershoot* line) {
  const Packing& p = t.packing;
  os << "trial " << end << ' ' << num(t.dt) << ' ' << num(t.E) << ' ' << to_string(t.start) << ' '
     << (t.deferred ? 1 : 0) << ' ' << p.size() << ' ' << p.next_id << ' ' << t.divisions.size();
  if (line) os << ' ' << num(line->phi) << ' ' << num(line->s) << ' ' << num(line->slope);
  os << '\n' << "rng " << t.rng << '\n';
  for (const Division& d : t.divisions)
    os << "division " << d.mother_index << ' ' << d.daughter_index << ' ' << d.mother_id << ' ' << d.daughter_id << ' '
       << num(d.x) << ' ' << num(d.y) << ' ' << num(d.theta) << ' ' << num(d.b) << '\n';
  write_cells(os, p);
}

// A growth attempt's relaxation in progress: its place and FIRE's state, the counters so far, then
// per cell its coordinates and velocities, per lobe where the neighbour lists were built.
void write_relaxation(std::ostream& os, const std::optional<RelaxationState>& relaxation) {
  os << "relaxation " << (relaxation ? 1 : 0);
  if (!relaxation) {
    os << '\n';
    return;
  }
  const RelaxationState& r = *relaxation;
  const FireProgress& f = r.progress;
  const std::size_t n = static_cast<std::size_t>(r.q.size() / 3);
  os << ' ' << r.attempts << ' ' << r.index << ' ' << n << ' ' << f.iteration << ' ' << num(f.dt) << ' ' << num(f.alpha)
     << ' ' << f.n_positive << ' ' << num(f.tol) << ' ' << num(f.newton_below) << ' ' << f.next_try << ' '
     << f.next_active_set << ' ' << f.active_set_tries << ' ' << f.undone << '\n';
  const FireResult& c = f.so_far;
  os << "relaxed " << c.iterations << ' ' << c.newton_iterations << ' ' << c.newton_chord_steps << ' '
     << c.active_set_steps << ' ' << c.active_set_factorisations << ' ' << c.active_set_updates << ' '
     << c.active_set_tries_undone << ' ' << c.evaluations << '\n';
  for (Eigen::Index k = 0; k < 3 * static_cast<Eigen::Index>(n); k += 3)
    os << num(r.q[k]) << ' ' << num(r.q[k + 1]) << ' ' << num(r.q[k + 2]) << ' ' << num(f.v[k]) << ' '
       << num(f.v[k + 1]) << ' ' << num(f.v[k + 2]) << '\n';
  const NeighbourList::Origin& o = f.neighbours;
  for (std::size_t a = 0; a < 2 * n; ++a)
    os << num(o.x0[a]) << ' ' << num(o.y0[a]) << ' ' << num(o.x1[a]) << ' ' << num(o.y1[a]) << '\n';
}

}  // namespace

bool CheckpointSchedule::due(long step, long evaluations, bool signal, bool complete) {
  if (step == 0) return false;
  const bool accepted = step != step_;
  const bool marginal = evaluations - evaluations_ > kMarginalEvaluations;
  step_ = step;
  evaluations_ = evaluations;
  const bool periodic = accepted && every_ > 0 && step % every_ == 0;
  return periodic || ((signal || marginal) && complete);
}

std::string checkpoint_blas() {
  std::istringstream words(blas_library());
  std::string line, word;
  while (words >> word) line.append(line.empty() ? "" : " ").append(escape_control(word));
  return line.empty() ? "unknown" : line;
}

std::uint64_t scene_hash(const Scene& scene) {
  Scene physics = scene;
  physics.threads = Scene{}.threads;
  return fnv1a64(scene_to_toml(physics));
}

std::string format_checkpoint(const Scene& scene, const GrowthState& s, const std::vector<Observer*>& observers) {
  const RunResult& r = s.result;
  std::ostringstream os;
  os << kCheckpointMagic << ' ' << kCheckpointVersion << '\n';
  os << "scene " << hex64(scene_hash(scene)) << '\n';
  os << "seed " << s.seed << '\n';
  os << "blas " << checkpoint_blas() << '\n';
  os << "rng " << s.rng << '\n';
  os << "state " << to_string(s.phase) << ' ' << num(s.dt) << ' ' << num(s.last_dt) << ' ' << num(s.last_log_scale)
     << ' ' << s.step << ' ' << s.attempts << ' ' << s.next_target << ' ' << s.divisions_since_jamming << ' '
     << s.episodes << '\n';
  os << "counters " << r.accepted << ' ' << r.rejected << ' ' << r.force_evaluations << ' ' << r.fire_iterations << ' '
     << r.divisions << ' ' << r.saddles_relaxed << ' ' << r.saddle_escapes << '\n';
  os << "cost " << r.search_trials << ' ' << r.marginal_relaxations << ' ' << r.newton_factorisations << ' '
     << r.newton_factor_reuses << ' ' << r.force_evaluations_initial << ' ' << r.force_evaluations_search << ' '
     << r.force_evaluations_above_jamming << ' ' << r.active_set_steps << ' ' << r.active_set_factorisations << ' '
     << r.active_set_updates << '\n';
  os << "branches " << r.branches << ' ' << r.branches_reached << ' ' << r.branch_stability_losses << ' '
     << r.branch_steps << ' ' << r.branch_events << ' ' << r.branch_rearrangements << '\n';
  os << "search " << s.search.slow_trials << ' ' << num(s.search.bracket_width) << ' ' << s.search.overshoots.size();
  for (const JammingOvershoot& o : s.search.overshoots)
    os << ' ' << num(o.phi) << ' ' << num(o.s) << ' ' << num(o.slope);
  os << '\n';
  os << "jamming " << (r.jamming ? 1 : 0);
  if (const auto& j = r.jamming)
    os << ' ' << j->episode << ' ' << j->step << ' ' << num(j->phi) << ' ' << num(j->P) << ' ' << num(j->E_per_cell)
       << ' ' << network_text(j->network) << ' ' << num(j->n_J) << ' ' << j->tagged;
  os << '\n';
  os << "targets " << r.targets.size() << '\n';
  for (const TargetRecord& t : r.targets)
    os << t.index << ' ' << num(t.dphi) << ' ' << num(t.phi_target) << ' ' << t.step << ' ' << num(t.phi) << ' '
       << num(t.P) << ' ' << num(t.E_per_cell) << ' ' << network_text(t.network) << ' ' << num(t.chi_c) << ' '
       << t.divisions_since_jamming << '\n';
  os << "depletion " << (r.depletion ? 1 : 0);
  if (const auto& d = r.depletion)
    os << ' ' << d->step << ' ' << num(d->phi) << ' ' << num(d->P) << ' ' << network_text(d->network) << ' '
       << d->still_unconstrained << ' ' << d->divisions_since_jamming;
  os << '\n';
  os << "unjammings " << r.unjammings.size() << '\n';
  for (const UnjamRecord& u : r.unjammings)
    os << u.episode << ' ' << u.step << ' ' << num(u.phi) << ' ' << num(u.phi_J) << ' ' << u.targets_lost << '\n';
  s.buds.save(os);
  const Packing& p = s.packing;
  os << "packing " << p.size() << ' ' << num(p.box.L) << ' ' << num(p.box.shear) << ' ' << p.next_id << '\n';
  write_cells(os, p);
  os << "bracket " << (s.search.bracket ? 1 : 0);
  if (const auto& b = s.search.bracket) {
    os << ' ' << b->slow_trials << ' ' << num(b->width) << ' ' << (b->below ? 1 : 0) << ' ' << b->above.size() << '\n';
    if (b->below) write_trial(os, "below", *b->below, nullptr);
    for (const BracketEnd& e : b->above) write_trial(os, "above", e.trial, &e.line);
  } else {
    os << '\n';
  }
  write_relaxation(os, s.relaxation);
  for (Observer* o : observers) {
    std::ostringstream body;
    o->save_state(body);
    std::string text = std::move(body).str();
    if (!text.empty() && text.back() != '\n') text += '\n';
    os << "observer " << o->name() << ' ' << std::count(text.begin(), text.end(), '\n') << '\n' << text;
  }
  os << "end\n";
  std::string out = std::move(os).str();
  out += std::string(kChecksum) + hex64(fnv1a64(out)) + '\n';
  return out;
}

void write_checkpoint(const Directory& dir, std::string_view name, const Scene& scene, const GrowthState& state,
                      const std::vector<Observer*>& observers) {
  write_atomically(dir, name, format_checkpoint(scene, state, observers));
}

// ---- parse_checkpoint: the framing, then one reader per line kind ---------------------------------

namespace {

// What the parse has read so far; each line kind's reader checks its line against it and fills
// its part of the state.
struct Parse {
  CheckpointText& in;
  const Scene& scene;
  std::uint64_t seed;
  GrowthState s;
  CheckpointLines where;  // where.buds: the tagged buds, checked against the packing

  // Cell counts are bounded by the cells that ever existed (checked against next_id by the packing).
  std::size_t cells_cap() const { return static_cast<std::size_t>(s.result.divisions) + 2 + scene.n_seeds; }
};

using Words = std::vector<std::string_view>;

// Versions this budjam refuses, with what they were written before.
constexpr std::pair<int, std::string_view> kRetiredVersions[] = {
    {1, "jamming candidates were checked for saddles (jamming.check_minimum)"},
    {2, "the secant jamming search (jamming.search)"},
    {3, "the secant jamming search (jamming.search)"},
    {4, "every record (jamming point, targets, phi_2) held the whole contact-network summary"},
    {5, "growth steps were stored with their log scale (the adaptive step out of the double range)"},
    {6, "the run counted its cost by stage (search trials, marginal relaxations, Newton factorisations)"},
    {7, "the run counted the relaxed branches it followed (jamming.continuation)"},
    {8, "the run counted the stability losses its branches crossed (jamming.crossing_step)"},
    {9, "the run counted its active-set steps (minimiser.active_set_after)"},
    {10, "a search onto phi_J was kept between its trials (the open bracket)"},
    {11, "the checkpoint recorded the BLAS its run computed with"},
    {12, "a growth attempt's relaxation could be checkpointed while it ran"},
    {13, "the run counted its steps off saddles"},
};

void read_version(CheckpointText& in) {
  const std::int64_t version = in.integer(in.next(kCheckpointMagic, 1)[0], "version", 0, kLongMax);
  for (const auto& [retired, before] : kRetiredVersions)
    if (version == retired)
      in.fail("checkpoint version " + std::to_string(version) + " was written before " + std::string(before) +
              "; start the run again");
  if (version != kCheckpointVersion)
    in.fail("checkpoint version " + std::to_string(version) + " is not supported (this budjam writes " +
            std::to_string(kCheckpointVersion) + "); start the run again");
}

// The checksum first: an edited or damaged file is refused before any of it is interpreted.
void verify_checksum(const CheckpointText& in, std::string_view text) {
  const std::size_t last = in.count();
  const std::string_view tail = in.raw(last);
  if (tail.substr(0, kChecksum.size()) != kChecksum) in.fail_at(last, "truncated: the last line is not the checksum");
  const std::string_view body = text.substr(0, text.size() - tail.size() - 1);
  if (tail.substr(kChecksum.size()) != hex64(fnv1a64(body)))
    in.fail_at(last, "checksum mismatch: the checkpoint was changed or damaged after it was written");
}

void read_scene(Parse& p, const Words& w) {
  if (w[0] != hex64(scene_hash(p.scene)))
    p.in.fail(
        "the run's scene.toml has changed since this checkpoint was written (its effective scene differs); "
        "a run cannot continue under other parameters");
}

void read_seed(Parse& p, const Words& w) {
  if (w[0] != std::to_string(p.seed) || !parse_int64(w[0]))
    p.in.fail("seed " + std::string(w[0]) + " does not match the run's seed " + std::to_string(p.seed));
  p.s.seed = p.seed;
}

void read_blas(Parse& p, const Words& w) {
  for (const auto& word : w) p.where.blas.append(p.where.blas.empty() ? "" : " ").append(word);
}

Rng random_stream(const CheckpointText& in, const Words& w) {
  std::string words;
  for (const auto& x : w) words.append(x).push_back(' ');
  std::istringstream rs(words);
  Rng rng;
  rs >> rng;
  std::string rest;
  if (!rs || (rs >> rest)) in.fail("rng: not the state of a mt19937_64 random stream");
  return rng;
}

void read_rng(Parse& p, const Words& w) { p.s.rng = random_stream(p.in, w); }

void read_state(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  GrowthState& s = p.s;
  p.where.state = in.line();
  if (w[0] == "jammed")
    s.phase = Phase::jammed;
  else if (w[0] == "unjammed")
    s.phase = Phase::unjammed;
  else
    in.fail("phase: expected jammed or unjammed, found '" + std::string(w[0]) + "'");
  // Steps are stored scaled (StepStart): the next one's scale follows from the state, so a dt
  // below growth.dt_min is left to the driver's next attempt (status dt_underflow).
  s.dt = in.positive(w[1], "dt");
  s.last_dt = in.positive(w[2], "last dt");
  s.last_log_scale = in.real(w[3], "last dt log scale");
  if (!(s.last_log_scale >= 0)) in.fail("last dt log scale: must be >= 0");
  s.attempts = in.integer(w[5], "attempts", 1, p.scene.max_steps);
  s.step = in.integer(w[4], "step", 1, s.attempts);
  s.next_target = in.count_of(w[6], "next target", p.scene.targets.size());
  s.divisions_since_jamming = in.integer(w[7], "divisions since jamming", 0, kLongMax);
  s.episodes = static_cast<int>(in.integer(w[8], "episodes", 0, s.step));
}

void read_counters(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const GrowthState& s = p.s;
  RunResult& r = p.s.result;
  p.where.counters = in.line();
  r.accepted = in.integer(w[0], "accepted", s.step, s.step);
  r.rejected = in.integer(w[1], "rejected", s.attempts - s.step, s.attempts - s.step);
  r.force_evaluations = in.integer(w[2], "force evaluations", s.attempts, kLongMax);
  r.fire_iterations = in.integer(w[3], "FIRE iterations", 0, kLongMax);
  r.divisions = in.integer(w[4], "divisions", s.divisions_since_jamming, static_cast<std::int64_t>(max_cells(p.scene)));
  r.saddles_relaxed = in.integer(w[5], "saddles relaxed", 0, s.attempts);
  r.saddle_escapes = in.integer(w[6], "saddle escapes", 0, r.saddles_relaxed * kSaddleEscapes);
}

void read_cost(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  RunResult& r = p.s.result;
  r.search_trials = in.integer(w[0], "search trials", 0, kLongMax);
  r.marginal_relaxations = in.integer(w[1], "marginal relaxations", 0, kLongMax);
  r.newton_factorisations = in.integer(w[2], "Newton factorisations", 0, kLongMax);
  r.newton_factor_reuses = in.integer(w[3], "Newton factor reuses", 0, kLongMax);
  r.force_evaluations_initial = in.integer(w[4], "initial force evaluations", 1, r.force_evaluations);
  r.force_evaluations_search = in.integer(w[5], "search force evaluations", 0, r.force_evaluations);
  r.force_evaluations_above_jamming = in.integer(w[6], "above-jamming force evaluations", 0, r.force_evaluations);
  r.active_set_steps = in.integer(w[7], "active-set steps", 0, kLongMax);
  r.active_set_factorisations = in.integer(w[8], "active-set factorisations", 0, kLongMax);
  r.active_set_updates = in.integer(w[9], "active-set updates", 0, kLongMax);
  if (r.force_evaluations_initial + r.force_evaluations_search + r.force_evaluations_above_jamming !=
      r.force_evaluations)
    in.fail("cost: the force evaluations by stage do not add up to the force evaluations");
}

void read_branches(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  RunResult& r = p.s.result;
  r.branches = in.integer(w[0], "branches", 0, p.s.attempts);
  r.branches_reached = in.integer(w[1], "branches reached", 0, r.branches);
  r.branch_stability_losses = in.integer(w[2], "branches that lost stability", 0, r.branches - r.branches_reached);
  r.branch_steps = in.integer(w[3], "branch steps", 0, kLongMax);
  r.branch_events = in.integer(w[4], "branch events", 0, kLongMax);
  r.branch_rearrangements = in.integer(w[5], "branch rearrangements", 0, kLongMax);
}

void read_search(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  if (w.size() < 3) in.fail("search: expected slow trials, bracket width and the number of overshoots");
  JammingSearchState& q = p.s.search;
  q.slow_trials = static_cast<int>(in.integer(w[0], "slow trials", 0, 2));
  q.bracket_width = in.real(w[1], "bracket width");
  if (!(q.bracket_width >= 0)) in.fail("bracket width: must be >= 0");
  const std::size_t n = in.count_of(w[2], "overshoots", static_cast<std::size_t>(p.s.attempts));
  if (w.size() != 3 + 3 * n)
    in.fail("search: expected " + std::to_string(3 + 3 * n) + " values, found " + std::to_string(w.size()));
  for (std::size_t k = 0; k < n; ++k) {
    JammingOvershoot o;
    o.phi = in.positive(w[3 + 3 * k], "overshoot phi");
    o.s = in.positive(w[4 + 3 * k], "overshoot sqrt(E/N)");
    o.slope = in.real(w[5 + 3 * k], "overshoot slope");
    if (k > 0 && o.phi < q.overshoots.back().phi) in.fail("overshoots: not sorted by phi");
    q.overshoots.push_back(o);
  }
}

// The flag (0 or 1) that opens the line of an optional record `key`.
bool record_flag(const CheckpointText& in, const Words& w, const std::string& key) {
  if (w.empty()) in.fail(key + ": expected 0 or 1");
  return in.flag(w[0], key.c_str());
}

// A present record has `size` words with its flag, an absent one the flag alone.
void check_record_size(const CheckpointText& in, const Words& w, const std::string& key, bool present,
                       std::size_t size) {
  if (present && w.size() != size)
    in.fail(key + ": expected " + std::to_string(size) + " values, found " + std::to_string(w.size()));
  if (!present && w.size() != 1) in.fail(key + ": expected no values after 0");
}

void read_jamming(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const GrowthState& s = p.s;
  p.where.jamming = in.line();
  const bool has = record_flag(in, w, "jamming");
  if (has != (s.phase == Phase::jammed)) in.fail("jamming: a record is present if and only if the phase is jammed");
  check_record_size(in, w, "jamming", has, 8 + kNetworkWords);
  if (!has) return;
  JammingRecord j;
  j.episode = static_cast<int>(in.integer(w[1], "jamming episode", s.episodes - 1, s.episodes - 1));
  j.step = in.integer(w[2], "jamming step", 1, s.step);
  j.phi = in.positive(w[3], "phi_J"), j.P = in.real(w[4], "P_J"), j.E_per_cell = in.real(w[5], "E_J");
  j.network = read_network(in, w, 6, p.cells_cap());
  j.n_J = in.real(w[6 + kNetworkWords], "n_J");
  j.tagged = in.count_of(w[7 + kNetworkWords], "tagged", j.network.N);
  p.s.result.jamming = j;
}

void read_targets(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const GrowthState& s = p.s;
  const std::size_t n = in.count_of(w[0], "targets", s.next_target);
  if (n != s.next_target)
    in.fail("targets: " + std::to_string(n) + " landed, but the next target is " + std::to_string(s.next_target));
  for (std::size_t k = 0; k < n; ++k) {
    const auto t_w = in.next("", 9 + kNetworkWords);
    p.where.targets.push_back(in.line());
    TargetRecord t;
    t.index = in.count_of(t_w[0], "target index", k);
    if (t.index != k) in.fail("target index: expected " + std::to_string(k));
    t.dphi = in.real(t_w[1], "dphi");
    if (t.dphi != p.scene.targets[k]) in.fail("dphi: not jamming.targets[" + std::to_string(k) + "] of the scene");
    t.phi_target = in.positive(t_w[2], "phi_target");
    t.step = in.integer(t_w[3], "target step", 1, s.step);
    t.phi = in.positive(t_w[4], "phi"), t.P = in.real(t_w[5], "P"), t.E_per_cell = in.real(t_w[6], "E_per_cell");
    t.network = read_network(in, t_w, 7, p.cells_cap());
    t.chi_c = in.real(t_w[7 + kNetworkWords], "chi_c");
    t.divisions_since_jamming =
        in.integer(t_w[8 + kNetworkWords], "divisions since jamming", 0, s.divisions_since_jamming);
    p.s.result.targets.push_back(t);
  }
}

void read_depletion(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const GrowthState& s = p.s;
  p.where.depletion = in.line();
  const bool has = record_flag(in, w, "depletion");
  if (has && s.phase != Phase::jammed) in.fail("depletion: recorded while unjammed");
  check_record_size(in, w, "depletion", has, 6 + kNetworkWords);
  if (!has) return;
  DepletionRecord d;
  d.step = in.integer(w[1], "phi_2 step", 1, s.step);
  d.phi = in.positive(w[2], "phi_2"), d.P = in.real(w[3], "P_2");
  d.network = read_network(in, w, 4, p.cells_cap());
  d.still_unconstrained = in.count_of(w[4 + kNetworkWords], "still unconstrained", p.scene.phi2_tagged_left);
  d.divisions_since_jamming = in.integer(w[5 + kNetworkWords], "divisions since jamming", 0, s.divisions_since_jamming);
  p.s.result.depletion = d;
}

void read_unjammings(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const GrowthState& s = p.s;
  const std::size_t ended = static_cast<std::size_t>(s.episodes - (s.phase == Phase::jammed ? 1 : 0));
  const std::size_t n = in.count_of(w[0], "unjammings", ended);
  if (n != ended)
    in.fail("unjammings: " + std::to_string(n) + " recorded, but " + std::to_string(ended) +
            " jamming episodes have ended");
  for (std::size_t k = 0; k < n; ++k) {
    const auto u_w = in.next("", 5);
    p.where.unjammings.push_back(in.line());
    UnjamRecord u;
    u.episode =
        static_cast<int>(in.integer(u_w[0], "episode", static_cast<std::int64_t>(k), static_cast<std::int64_t>(k)));
    u.step = in.integer(u_w[1], "unjamming step", 1, s.step);
    u.phi = in.positive(u_w[2], "phi"), u.phi_J = in.positive(u_w[3], "phi_J");
    u.targets_lost = in.count_of(u_w[4], "targets lost", p.scene.targets.size());
    p.s.result.unjammings.push_back(u);
  }
}

// The tagged buds go through BudTags::load (as text) and are checked against the packing later.
void read_buds(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const std::size_t buds_line = in.line();
  const std::int64_t episode = in.integer(w[0], "buds episode", 0, p.s.episodes);
  const std::size_t n = in.count_of(w[1], "tagged buds", p.cells_cap());
  std::string buds_text = "buds " + std::to_string(episode) + ' ' + std::to_string(n) + '\n';
  std::int64_t previous = -1;
  for (std::size_t k = 0; k < n; ++k) {
    const auto t = in.next("", 4);
    const std::int64_t id = in.integer(t[0], "bud id", previous + 1, std::numeric_limits<std::int64_t>::max());
    const double b2_J = in.real(t[1], "b_J squared");
    in.flag(t[2], "touched");
    in.integer(t[3], "bud state", 0, 3);
    previous = id;
    p.where.buds.push_back({id, b2_J, in.line()});
    for (const auto& x : t) buds_text.append(x).push_back(' ');
    buds_text.back() = '\n';
  }
  std::istringstream bs(buds_text);
  try {
    p.s.buds.load(bs);
  } catch (const std::exception& e) {
    in.fail_at(buds_line, std::string("buds: ") + e.what());
  }
}

// `n` cells (ids below next_id, unique) into `pk`, whose box is set, each obeying the physical rules.
std::unordered_set<std::int64_t> read_cells(CheckpointText& in, const Scene& scene, std::size_t n, std::int64_t next_id,
                                            Packing& pk) {
  std::unordered_set<std::int64_t> ids;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = in.next("", 7);
    const double x = in.real(c[0], "x"), y = in.real(c[1], "y"), th = in.real(c[2], "theta");
    const double b = in.real(c[3], "b"), g0 = in.real(c[4], "gamma0");
    const std::int64_t id = in.integer(c[5], "id", 0, next_id - 1);
    const std::int64_t parent = in.integer(c[6], "parent", -1, next_id - 1);
    if (!ids.insert(id).second) in.fail("id " + std::to_string(id) + ": duplicate");
    if (parent == id) in.fail("parent: a cell is not its own mother");
    pk.add_cell(x, y, th, b, g0, parent);
    pk.id.back() = id;
    if (const auto problem = cell_problem(pk, i, max_bud_diameter(scene.alpha0))) in.fail(*problem);
  }
  pk.next_id = next_id;
  if (const auto problem = box_problem(pk, scene.skin)) in.fail(*problem);
  return ids;
}

void read_packing(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const Scene& scene = p.scene;
  const std::size_t cells_cap = p.cells_cap();
  const std::size_t n = in.count_of(w[0], "cells", cells_cap);
  if (n == 0) in.fail("packing: no cells");
  Packing& pk = p.s.packing;
  pk.box.L = in.positive(w[1], "L");
  if (pk.box.L != scene.L) in.fail("L: does not match the scene's box.L");
  pk.box.shear = in.real(w[2], "shear");
  if (pk.box.shear != 0) in.fail("shear: a growing packing is never sheared (expected 0)");
  const std::int64_t next_id =
      in.integer(w[3], "next id", static_cast<std::int64_t>(n), static_cast<std::int64_t>(cells_cap));
  const std::unordered_set<std::int64_t> ids = read_cells(in, scene, n, next_id, pk);
  for (const auto& t : p.where.buds)
    if (!ids.count(t.id)) in.fail_at(t.line, "bud id " + std::to_string(t.id) + ": no cell of the packing has it");
}

// The cells of an open bracket's trial, grown from the accepted packing: the same cells first
// (a dividing mother keeps its index and id), then one daughter per division, in order.
Trial read_trial(Parse& p, const Words& w, bool upper, JammingOvershoot* line) {
  CheckpointText& in = p.in;
  const Packing& accepted = p.s.packing;
  const std::size_t header = in.line();
  Trial t;
  t.dt = in.positive(w[1], "trial dt");
  t.E = in.real(w[2], "trial E/N");
  if (!(t.E >= 0)) in.fail("trial E/N: must be >= 0");
  if (w[3] == to_string(TrialStart::accepted_state))
    t.start = TrialStart::accepted_state;
  else if (w[3] == to_string(TrialStart::lowest_overshoot))
    t.start = TrialStart::lowest_overshoot;
  else
    in.fail("trial start: expected accepted_state or lowest_overshoot, found '" + std::string(w[3]) + "'");
  t.deferred = in.flag(w[4], "deferred");
  const std::size_t cap = max_cells(p.scene);
  const std::size_t n = in.count_of(w[5], "trial cells", cap);
  const std::size_t born = in.count_of(w[7], "trial divisions", cap);
  if (n != accepted.size() + born)
    in.fail("trial cells: " + std::to_string(n) + ", but the accepted packing's " + std::to_string(accepted.size()) +
            " and " + std::to_string(born) + " divisions make " + std::to_string(accepted.size() + born));
  const std::int64_t next_id = in.integer(w[6], "trial next id", accepted.next_id + static_cast<std::int64_t>(born),
                                          accepted.next_id + static_cast<std::int64_t>(born));
  const JammingWindow window = jamming_window(p.scene);
  if (upper) {
    line->phi = in.positive(w[8], "overshoot phi");
    line->s = in.real(w[9], "overshoot sqrt(E/N)");
    line->slope = in.real(w[10], "overshoot slope");
    if (!(line->slope >= 0)) in.fail("overshoot slope: must be >= 0");
    if (window.side(t.E) == WindowSide::below) in.fail("trial E/N: an upper end of the bracket is below the window");
    if (line->s != std::sqrt(t.E)) in.fail("overshoot sqrt(E/N): not the square root of the trial's E/N");
  } else {
    if (t.deferred) in.fail("deferred: the lower end of the bracket is relaxed");
    if (window.side(t.E) != WindowSide::below)
      in.fail("trial E/N: the lower end of the bracket is not below the window");
  }
  t.rng = random_stream(in, in.next("rng", -1));
  for (std::size_t k = 0; k < born; ++k) {
    const auto d_w = in.next("division", 8);
    Division d;
    d.daughter_index = in.count_of(d_w[1], "daughter index", n);
    if (d.daughter_index != accepted.size() + k)
      in.fail("daughter index: expected " + std::to_string(accepted.size() + k) + " (daughters are appended in order)");
    d.mother_index = in.count_of(d_w[0], "mother index", d.daughter_index - 1);
    d.mother_id = in.integer(d_w[2], "mother id", 0, next_id - 1);
    d.daughter_id = in.integer(d_w[3], "daughter id", 0, next_id - 1);
    d.x = in.real(d_w[4], "x"), d.y = in.real(d_w[5], "y"), d.theta = in.real(d_w[6], "theta");
    d.b = in.real(d_w[7], "b");
    t.divisions.push_back(d);
  }
  t.packing.box = accepted.box;
  read_cells(in, p.scene, n, next_id, t.packing);
  const Packing& q = t.packing;
  for (std::size_t i = 0; i < accepted.size(); ++i)
    if (q.id[i] != accepted.id[i])
      in.fail_at(header + 2 + born + i, "id: not that of the accepted packing's cell " + std::to_string(i));
  for (std::size_t k = 0; k < born; ++k) {
    const Division& d = t.divisions[k];
    if (q.id[d.mother_index] != d.mother_id || q.id[d.daughter_index] != d.daughter_id ||
        q.parent[d.daughter_index] != d.mother_id)
      in.fail_at(header + 2 + k, "division: the trial's cells do not record it (ids and parent)");
  }
  if (upper && line->phi != q.packing_fraction())
    in.fail_at(header, "overshoot phi: not the packing fraction of the trial");
  return t;
}

// An open bracket (the bracket search between two trials): its lower end, then its upper ends by
// increasing Δt, all from the accepted state, the accepted state unjammed.
void read_bracket(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const bool open = record_flag(in, w, "bracket");
  check_record_size(in, w, "bracket", open, 5);
  if (!open) return;
  if (p.scene.search != JammingSearch::bracket) in.fail("bracket: the scene's jamming.search is not bracket");
  if (p.s.phase != Phase::unjammed) in.fail("bracket: open while jammed (a bracket searches for phi_J)");
  OpenBracket b;
  b.slow_trials = static_cast<int>(in.integer(w[1], "slow trials", 0, 2));
  b.width = in.real(w[2], "bracket width");
  if (!(b.width >= 0)) in.fail("bracket width: must be >= 0");
  const bool below = in.flag(w[3], "lower end");
  const std::size_t ends = in.count_of(w[4], "upper ends", static_cast<std::size_t>(p.s.attempts));
  if (!below && ends == 0) in.fail("bracket: neither a lower nor an upper end");
  if (below) {
    const auto t_w = in.next("trial", 8);
    if (t_w[0] != "below") in.fail("trial: expected the lower end ('trial below ...')");
    b.below = read_trial(p, t_w, false, nullptr);
  }
  for (std::size_t k = 0; k < ends; ++k) {
    const auto t_w = in.next("trial", 11);
    if (t_w[0] != "above") in.fail("trial: expected an upper end ('trial above ...')");
    const std::size_t header = in.line();
    BracketEnd e;
    e.trial = read_trial(p, t_w, true, &e.line);
    const double lower = k ? b.above.back().trial.dt : (b.below ? b.below->dt : 0.0);
    if (!(e.trial.dt > lower)) in.fail_at(header, "trial dt: the bracket's ends are not in increasing dt");
    b.above.push_back(std::move(e));
  }
  p.s.search.bracket = std::move(b);
}

// A relaxation in progress (write_relaxation). Whether its cells are those the attempt grows is
// known only once the resumed run makes the attempt (GrowthDriver::restore).
void read_relaxation(Parse& p, const Words& w) {
  CheckpointText& in = p.in;
  const bool present = record_flag(in, w, "relaxation");
  check_record_size(in, w, "relaxation", present, 14);
  if (!present) return;
  const GrowthState& s = p.s;
  RelaxationState r;
  // A grown trial counts its attempt before its relaxation; a deferred trial resumed or a bracket
  // settled is an attempt already counted.
  r.attempts = in.integer(w[1], "relaxation attempt", s.attempts, std::min(s.attempts + 1, p.scene.max_steps));
  r.index = static_cast<int>(in.integer(w[2], "relaxation index", 0, 2));
  const std::size_t n = in.count_of(w[3], "relaxation cells", max_cells(p.scene));
  if (n == 0) in.fail("relaxation cells: none");
  FireProgress& f = r.progress;
  f.iteration = in.integer(w[4], "relaxation iteration", 1, kLongMax);
  f.dt = in.positive(w[5], "relaxation FIRE dt");
  const double dt_cap = std::max(p.scene.fire.dt_max, p.scene.fire.dt_start);
  if (!(f.dt <= dt_cap)) in.fail("relaxation FIRE dt: above the scene's minimiser.dt_max");
  f.alpha = in.real(w[6], "relaxation FIRE alpha");
  if (!(f.alpha >= 0 && f.alpha <= 1)) in.fail("relaxation FIRE alpha: must be in [0, 1]");
  f.n_positive = in.integer(w[7], "relaxation steps with positive power", 0, f.iteration);
  f.tol = in.positive(w[8], "relaxation force tolerance");
  f.newton_below = in.real(w[9], "relaxation Newton threshold");
  if (!(f.newton_below >= 0)) in.fail("relaxation Newton threshold: must be >= 0");
  f.next_try = in.integer(w[10], "relaxation next active-set try", 0, kLongMax);
  f.next_active_set = in.integer(w[11], "relaxation next active-set steps", 0, kLongMax);
  f.active_set_tries = in.integer(w[12], "relaxation active-set hand-overs", 0, kLongMax);
  const std::size_t header = in.line();
  const auto c_w = in.next("relaxed", 8);
  FireResult& c = f.so_far;
  c.iterations = in.integer(c_w[0], "relaxed iterations", f.iteration - 1, f.iteration - 1);
  c.newton_iterations = in.integer(c_w[1], "relaxed Newton steps", 0, kLongMax);
  c.newton_chord_steps = in.integer(c_w[2], "relaxed Newton chord steps", 0, kLongMax);
  c.active_set_steps = in.integer(c_w[3], "relaxed active-set steps", 0, kLongMax);
  c.active_set_factorisations = in.integer(c_w[4], "relaxed active-set factorisations", 0, c.active_set_steps);
  c.active_set_updates = in.integer(c_w[5], "relaxed active-set updates", 0, kLongMax);
  c.active_set_tries_undone = in.integer(c_w[6], "relaxed active-set tries undone", 0, kLongMax);
  c.evaluations = in.integer(c_w[7], "relaxed force evaluations", c.iterations, kLongMax);
  f.undone = in.integer(w[13], "relaxation evaluations undone", 0, kLongMax);
  if (f.undone > c.evaluations) in.fail_at(header, "relaxation evaluations undone: more than its evaluations");
  const Eigen::Index m = 3 * static_cast<Eigen::Index>(n);
  r.q.resize(m);
  f.v.resize(m);
  // Positions within the packing rules' reach of the box; no FIRE step crosses a box.
  const double far = kMaxBoxesAway * p.scene.L;
  const auto position = [&](std::string_view word, const char* what) {
    const double x = in.real(word, what);
    if (!(std::abs(x) <= far)) in.fail(std::string(what) + ": more than " + num(kMaxBoxesAway) + " box sides away");
    return x;
  };
  for (Eigen::Index k = 0; k < m; k += 3) {
    const auto x = in.next("", 6);
    r.q[k] = position(x[0], "x"), r.q[k + 1] = position(x[1], "y"), r.q[k + 2] = in.real(x[2], "theta");
    for (int j = 0; j < 3; ++j) {
      f.v[k + j] = in.real(x[3 + j], "velocity");
      if (!(std::abs(f.v[k + j]) * dt_cap <= p.scene.L)) in.fail("velocity: a FIRE step would cross the box");
    }
  }
  NeighbourList::Origin& o = f.neighbours;
  for (std::size_t a = 0; a < 2 * n; ++a) {
    const auto x = in.next("", 4);
    o.x0.push_back(position(x[0], "lobe x at the pair list's build"));
    o.y0.push_back(position(x[1], "lobe y at the pair list's build"));
    o.x1.push_back(position(x[2], "lobe x at the near list's build"));
    o.y1.push_back(position(x[3], "lobe y at the near list's build"));
  }
  p.s.relaxation = std::move(r);
}

// The lines between the header and the observer sections, in the order format_checkpoint writes
// them. A line `key w1 ... wn` is split into words, `key` checked, then `read` checks and stores
// the words (and reads the rows that follow a count, if any).
struct LineKind {
  std::string_view key;
  long words;  // after the key; -1: any number, checked by `read`
  void (*read)(Parse&, const Words&);
};

constexpr LineKind kLineKinds[] = {
    {"scene", 1, read_scene},
    {"seed", 1, read_seed},
    {"blas", -1, read_blas},
    {"rng", -1, read_rng},
    {"state", 9, read_state},
    {"counters", 7, read_counters},
    {"cost", 10, read_cost},
    {"branches", 6, read_branches},
    {"search", -1, read_search},
    {"jamming", -1, read_jamming},
    {"targets", 1, read_targets},
    {"depletion", -1, read_depletion},
    {"unjammings", 1, read_unjammings},
    {"buds", 2, read_buds},
    {"packing", 4, read_packing},
    {"bracket", -1, read_bracket},
    {"relaxation", -1, read_relaxation},
};

// The observer sections up to the line `end`, each observer named once.
std::vector<Section> read_sections(CheckpointText& in) {
  const std::size_t last = in.count();
  std::vector<Section> sections;
  while (in.line() + 1 < last && in.raw(in.line() + 1).substr(0, 9) == "observer ") {
    const auto w = in.next("observer", 2);
    Section sec{std::string(w[0]), in.line(), {}};
    const std::size_t lines = in.count_of(w[1], "section lines", last - in.line() - 1);
    for (std::size_t k = 0; k < lines; ++k) sec.body.append(in.take()).push_back('\n');
    for (const Section& other : sections)
      if (other.name == sec.name) in.fail("observer '" + sec.name + "': two sections");
    sections.push_back(std::move(sec));
  }
  in.next("end", 0);
  if (in.line() + 1 != last) in.fail_at(in.line() + 1, "unexpected line after 'end'");
  return sections;
}

// Hands each observer its section, once every section is known to belong to one.
void load_observers(const CheckpointText& in, const std::vector<Section>& sections,
                    const std::vector<Observer*>& observers) {
  const std::size_t last = in.count();
  std::vector<std::pair<Observer*, const Section*>> matched;
  for (Observer* o : observers) {
    const Section* found = nullptr;
    for (const Section& sec : sections)
      if (sec.name == o->name()) found = &sec;
    if (!found && o->stateful())
      in.fail_at(last, "no section for observer '" + o->name() +
                           "': the run has an observer the checkpoint does not know (was the scene edited?)");
    if (found) matched.emplace_back(o, found);
  }
  for (const Section& sec : sections) {
    bool known = false;
    for (Observer* o : observers) known |= o->name() == sec.name;
    if (!known && !sec.body.empty())
      in.fail_at(sec.line, "state saved for observer '" + sec.name + "', which this run does not have");
  }
  for (const auto& [o, sec] : matched) {
    std::istringstream is(sec->body);
    try {
      o->load_state(is);
    } catch (const std::exception& e) {
      in.fail_at(sec->line, "observer '" + sec->name + "': " + e.what());
    }
  }
}

}  // namespace

GrowthState parse_checkpoint(std::string_view text, const std::string& file, const Scene& scene, std::uint64_t seed,
                             const std::vector<Observer*>& observers, CheckpointLines* lines) {
  CheckpointText in(text, file);
  read_version(in);
  verify_checksum(in, text);
  Parse p{in, scene, seed, {}, {}};
  for (const LineKind& kind : kLineKinds) kind.read(p, in.next(kind.key, kind.words));
  // Observers' load_state runs only once everything above has passed.
  load_observers(in, read_sections(in), observers);
  if (lines) *lines = std::move(p.where);
  return std::move(p.s);
}

// ---- the checkpoint against the run's logs and packings ----------------------------------------

StepsLog read_steps(std::string_view steps_text, const std::string& file) {
  auto fields = [](std::string_view line) {
    std::vector<std::string_view> f;
    for (std::size_t at = 0, end = 0; end != std::string_view::npos; at = end + 1)
      f.push_back(line.substr(at, (end = line.find(',', at)) - at));
    return f;
  };
  std::size_t at = std::min(steps_text.find('\n'), steps_text.size());
  const std::vector<std::string_view> columns = fields(steps_text.substr(0, at));
  auto column = [&](std::string_view name) {
    const auto c = std::find(columns.begin(), columns.end(), name);
    if (c == columns.end()) throw InputError(escape_control(file + ":1: no column " + std::string(name)));
    return static_cast<std::size_t>(c - columns.begin());
  };
  const std::size_t step = column("step"), N = column("N"), phi = column("phi"), P = column("P"),
                    phase = column("phase"), chi_c = column("chi_c");
  StepsLog log;
  Phase previous = Phase::unjammed;  // a run never starts jammed
  for (std::size_t line = 2; at + 1 < steps_text.size(); ++line) {
    const std::size_t end = std::min(steps_text.find('\n', at + 1), steps_text.size());
    const std::vector<std::string_view> f = fields(steps_text.substr(at + 1, end - at - 1));
    at = end;
    const bool whole = f.size() == columns.size();
    const auto n = whole ? parse_int64(f[step]) : std::nullopt;
    const auto cells = whole ? parse_int64(f[N]) : std::nullopt;
    const auto x = whole ? parse_double(f[phi]) : std::nullopt;
    const auto p = whole ? parse_double(f[P]) : std::nullopt;
    // χ_c is written exactly at any size (beyond the double range as decimal text), empty before jamming
    const auto chi = whole ? tools::csv_number(std::string(f[chi_c])) : std::nullopt;
    const std::string_view word = whole ? f[phase] : std::string_view();
    if (!n || !cells || !x || !p || !chi || (word != to_string(Phase::jammed) && word != to_string(Phase::unjammed)))
      throw InputError(
          escape_control(file + ":" + std::to_string(line) + ": not a row with a step, N, phi, P, phase and chi_c"));
    const Phase now = word == to_string(Phase::jammed) ? Phase::jammed : Phase::unjammed;
    log.rows.push_back({static_cast<long>(*n), static_cast<std::size_t>(*cells), *x, *p, *chi, now});
    if (now != previous) log.changes.push_back(log.rows.back());
    previous = now;
  }
  return log;
}

namespace {

// φ and P computed again from a packing's cells: the sums may run in another order than the run's.
bool near(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b)); }

// One checkpoint record against the packing saved with it.
struct RecordCheck {
  const std::string& file;
  std::size_t line;
  const PackingFile& pack;
  std::string pack_name;

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(escape_control(file + ":" + std::to_string(line) + ": " + what));
  }
  void same(const std::string& key, double recorded) const {
    const double saved = pack.meta.number(key);
    if (!(saved == recorded))
      fail(key + " = " + format_double(recorded) + " disagrees with " + pack_name + " (" + key + " = " +
           format_double(saved) + ")");
  }
  void network(const NetworkSummary& n) const {
    if (pack.packing.size() != n.N)
      fail("N = " + std::to_string(n.N) + " disagrees with " + pack_name + " (" + std::to_string(pack.packing.size()) +
           " cells)");
    same("N_nr", static_cast<double>(n.N_nr));
    same("Z", n.Z);
  }
  // The record as the packing's cells give it, not only as its meta lines say: the contact network
  // counted afresh, φ and the contact pressure P (these two to 10⁻¹² relative: the sums may run in
  // another order than the run's).
  void cells(const NetworkSummary& n, double phi, double P) const {
    const tools::PackingContacts pc = tools::analyse_contacts(pack.packing);
    const NetworkSummary& c = pc.network;
    const std::pair<const char*, std::pair<double, double>> counts[] = {
        {"N_nr", {double(n.N_nr), double(c.N_nr)}},
        {"N_f", {double(n.N_f), double(c.N_f)}},
        {"N_f_single_pass", {double(n.N_f_single_pass), double(c.N_f_single_pass)}},
        {"N_c", {double(n.N_c), double(c.N_c)}},
        {"N_u", {double(n.N_u), double(c.N_u)}},
        {"N_u_buds", {double(n.N_u_buds), double(c.N_u_buds)}},
        {"Z", {n.Z, c.Z}},
        {"u", {n.u, c.u}},
        {"u_buds", {n.u_buds, c.u_buds}},
        {"Z_iso", {n.Z_iso, c.Z_iso}},
        {"dZ", {n.dZ, c.dZ}}};
    for (const auto& [name, v] : counts)
      if (!(v.first == v.second))
        fail(std::string(name) + " = " + format_double(v.first) + ", but the cells of " + pack_name + " give " +
             format_double(v.second));
    if (!near(phi, pack.packing.packing_fraction()))
      fail("phi = " + format_double(phi) + ", but the cells of " + pack_name + " give " +
           format_double(pack.packing.packing_fraction()));
    if (!near(P, pc.P))
      fail("P = " + format_double(P) + ", but the cells of " + pack_name + " give " + format_double(pc.P));
  }
};

// Jamming episodes alternate in steps.csv: the k-th change to jammed is episode k's jamming point,
// the k-th change back its unjamming, and the last row is in the checkpoint's phase.
template <class Fail>
void check_phase_changes(const GrowthState& s, const CheckpointLines& at, const std::vector<StepRow>& changes,
                         Fail fail) {
  const std::string steps_name = std::string(run_files::steps) + ".partial";
  const RunResult& r = s.result;
  const std::size_t jammings = (changes.size() + 1) / 2, unjammings = changes.size() / 2;
  if (jammings != static_cast<std::size_t>(s.episodes) || unjammings != r.unjammings.size())
    fail(at.state, std::to_string(s.episodes) + " jamming episodes with " + std::to_string(r.unjammings.size()) +
                       " unjammings, but the phase column of " + steps_name + " changes to jammed " +
                       std::to_string(jammings) + " and back " + std::to_string(unjammings) +
                       " times up to the recorded length");
  const Phase last = changes.empty() ? Phase::unjammed : changes.back().phase;
  if (last != s.phase)
    fail(at.state,
         "phase " + std::string(to_string(s.phase)) + ", but the last row of " + steps_name + " is " + to_string(last));
  auto describe = [&](const StepRow& c) {
    return "step " + std::to_string(c.step) + " at phi = " + format_double(c.phi);
  };
  for (std::size_t k = 0; k < r.unjammings.size(); ++k) {
    const UnjamRecord& u = r.unjammings[k];
    const StepRow &jam = changes[2 * k], &unjam = changes[2 * k + 1];
    if (u.step != unjam.step || u.phi != unjam.phi || u.phi_J != jam.phi)
      fail(at.unjammings[k], "unjamming " + std::to_string(k) + " at step " + std::to_string(u.step) + ", phi = " +
                                 format_double(u.phi) + " from phi_J = " + format_double(u.phi_J) + ", but " +
                                 steps_name + " jams at " + describe(jam) + " and unjams at " + describe(unjam));
  }
  if (r.jamming && (r.jamming->step != changes.back().step || r.jamming->phi != changes.back().phi))
    fail(at.jamming, "jamming point at step " + std::to_string(r.jamming->step) +
                         ", phi = " + format_double(r.jamming->phi) + ", but " + steps_name + " jams at " +
                         describe(changes.back()));
}

}  // namespace

void check_against_run(const GrowthState& s, const Scene& scene, const CheckpointLines& at, const std::string& file,
                       const CsvLog::Cut& steps, const StepsLog& log, const CsvLog::Cut& divisions,
                       const Directory& packings) {
  auto fail = [&](std::size_t line, const std::string& what) {
    throw InputError(escape_control(file + ":" + std::to_string(line) + ": " + what));
  };
  // steps.csv has a row for the initial state (step 0) and one per accepted step.
  const std::string steps_name = std::string(run_files::steps) + ".partial";
  if (steps.rows != static_cast<std::size_t>(s.step) + 1)
    fail(at.state, "step " + std::to_string(s.step) + ", but " + steps_name + " holds " + std::to_string(steps.rows) +
                       " rows up to the recorded length (expected one per step from 0)");
  const std::string last_step = steps.last_row.substr(0, steps.last_row.find(','));
  if (last_step != std::to_string(s.step))
    fail(at.state, "step " + std::to_string(s.step) + ", but the last row of " + steps_name + " is step " + last_step);
  // The accepted state as its last row logged it (φ and P to 10⁻¹², as the records' cells).
  if (!log.rows.empty()) {
    const StepRow& last = log.rows.back();
    const double phi = s.packing.packing_fraction(), P = tools::analyse_contacts(s.packing).P;
    if (last.N != s.packing.size() || !near(last.phi, phi) || !near(last.P, P))
      fail(at.state, "the packing has N = " + std::to_string(s.packing.size()) + ", phi = " + format_double(phi) +
                         ", P = " + format_double(P) + ", but the last row of " + steps_name + " has " +
                         std::to_string(last.N) + ", " + format_double(last.phi) + ", " + format_double(last.P));
  }
  // steps.csv's last column: the divisions since jamming, empty while unjammed
  const std::string since = steps.last_row.substr(steps.last_row.rfind(',') + 1);
  if (s.phase == Phase::jammed && since != std::to_string(s.divisions_since_jamming))
    fail(at.state, std::to_string(s.divisions_since_jamming) + " divisions since jamming, but the last row of " +
                       steps_name + " has " + (since.empty() ? "none" : since));
  if (divisions.rows != static_cast<std::size_t>(s.result.divisions))
    fail(at.counters, "divisions " + std::to_string(s.result.divisions) + ", but " + std::string(run_files::divisions) +
                          ".partial holds " + std::to_string(divisions.rows) + " rows up to the recorded length");

  auto saved = [&](std::size_t line, const std::string& stem) {
    const std::string name = stem + ".pack";
    if (!packings.entry(name))
      fail(line, "the record has no saved packing " + (std::filesystem::path(run_files::packings) / name).string());
    return parse_packing(read_text_file(packings, name), (packings / name).string());
  };
  auto common = [&](const RecordCheck& c, long step, double phi, double P) {
    c.same("step", static_cast<double>(step));
    c.same("phi", phi);
    c.same("P", P);
    c.same("seed", static_cast<double>(s.seed));
    if (scene.P0)
      c.same("P0", *scene.P0);
    else if (c.pack.meta.get("P0") != "none")
      c.fail("the scene has no P0 (no feedback), but " + c.pack_name +
             " was grown with P0 = " + c.pack.meta.get("P0").value_or("?"));
  };
  const RunResult& r = s.result;
  if (r.jamming) {
    const PackingFile pack = saved(at.jamming, std::string(run_files::jammed));
    const RecordCheck c{file, at.jamming, pack, "packings/jammed.pack"};
    common(c, r.jamming->step, r.jamming->phi, r.jamming->P);
    c.same("E_per_cell", r.jamming->E_per_cell);
    c.network(r.jamming->network);
    c.cells(r.jamming->network, r.jamming->phi, r.jamming->P);
    const double L = pack.packing.box.L;
    if (!(r.jamming->n_J == static_cast<double>(r.jamming->network.N_nr) / (L * L)))
      c.fail("n_J = " + format_double(r.jamming->n_J) + ", but its N_nr / L^2 is " +
             format_double(static_cast<double>(r.jamming->network.N_nr) / (L * L)));
    if (s.buds.episode() == r.jamming->episode && r.jamming->tagged != at.buds.size())
      c.fail(std::to_string(r.jamming->tagged) + " buds tagged at jamming, but the checkpoint follows " +
             std::to_string(at.buds.size()));
    if (s.buds.episode() == r.jamming->episode)
      for (const auto& tag : at.buds) {
        const auto& ids = pack.packing.id;
        const auto it = std::find(ids.begin(), ids.end(), tag.id);
        const double b = it == ids.end() ? -1.0 : pack.packing.b[static_cast<std::size_t>(it - ids.begin())];
        if (it == ids.end() || b * b != tag.b2_J)
          fail(tag.line,
               "tagged bud " + std::to_string(tag.id) + ": b_J² = " + format_double(tag.b2_J) +
                   " disagrees with packings/jammed.pack" +
                   (it == ids.end() ? std::string(" (no such cell)") : " (b² = " + format_double(b * b) + ")"));
      }
  }
  for (std::size_t k = 0; k < r.targets.size(); ++k) {
    const TargetRecord& t = r.targets[k];
    const std::string stem = run_files::target_stem(t.index);
    const PackingFile pack = saved(at.targets[k], stem);
    const RecordCheck c{file, at.targets[k], pack, "packings/" + stem + ".pack"};
    common(c, t.step, t.phi, t.P);
    c.same("E_per_cell", t.E_per_cell);
    c.same("dphi", t.dphi);
    c.network(t.network);
    c.cells(t.network, t.phi, t.P);
  }
  if (r.depletion) {
    const PackingFile pack = saved(at.depletion, std::string(run_files::phi2));
    const RecordCheck c{file, at.depletion, pack, "packings/phi2.pack"};
    common(c, r.depletion->step, r.depletion->phi, r.depletion->P);
    c.network(r.depletion->network);
    c.cells(r.depletion->network, r.depletion->phi, r.depletion->P);
  }
  for (std::size_t k = 0; k < s.result.targets.size(); ++k) {
    const TargetRecord& t = s.result.targets[k];
    const auto row = t.step >= 0 && static_cast<std::size_t>(t.step) < log.rows.size()
                         ? std::optional<StepRow>(log.rows[static_cast<std::size_t>(t.step)])
                         : std::nullopt;
    if (!row || row->step != t.step || !(row->chi_c == t.chi_c))
      fail(at.targets[k], "chi_c = " + format_double(t.chi_c) + " at step " + std::to_string(t.step) + ", but " +
                              steps_name + " has " + (row ? format_double(row->chi_c) : std::string("no such row")));
    if (s.result.jamming && !(t.phi_target == s.result.jamming->phi + t.dphi))
      fail(at.targets[k], "phi_target = " + format_double(t.phi_target) +
                              ", but phi_J + dphi = " + format_double(s.result.jamming->phi + t.dphi));
  }
  check_phase_changes(s, at, log.changes, [&](std::size_t line, const std::string& what) { fail(line, what); });
}

GrowthState read_checkpoint(const Directory& dir, std::string_view name, const Scene& scene, std::uint64_t seed,
                            const std::vector<Observer*>& observers, CheckpointLines* lines) {
  return parse_checkpoint(read_text_file(dir, name), (dir / name).string(), scene, seed, observers, lines);
}

}  // namespace budjam::io
