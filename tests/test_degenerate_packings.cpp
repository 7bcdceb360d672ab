// Degenerate packings: the reader's geometric rules (packing_rules.hpp: φ < 4, no pair of lobes of
// different cells overlapping by half its contact distance) and what moduli, dos and rigidity do
// with every packing the reader accepts: a result with finite numbers (exit 0), a notice (exit 1)
// or a refusal naming the file (exit 2); never NaN with success, never "internal", bounded time.
#include "budjam/cell_list.hpp"
#include "budjam/packing_rules.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>

using namespace budjam;
using budjam::testing::work_dir;
using Catch::Matchers::Contains;

namespace {

std::string error_of(const Packing& p) {
  try {
    io::parse_packing(io::format_packing(p), "d.pack");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

Packing box_of(double L, double shear = 0) {
  Packing p;
  p.box.L = L;
  p.box.shear = shear;
  return p;
}

// The O(N²) oracle: the pair of cells (by lobe, lowest first) that the overlap rule refuses, if any.
std::optional<std::pair<std::size_t, std::size_t>> brute_force_violation(const Packing& p) {
  Lobes l;
  place_lobes(p, l);
  auto overlapping = brute_force_pairs(l, p.box, 0);
  std::sort(overlapping.begin(), overlapping.end());
  for (const auto& [a, b] : overlapping) {
    double dx = l.x[b] - l.x[a], dy = l.y[b] - l.y[a];
    p.box.minimum_image(dx, dy);
    if (std::hypot(dx, dy) <= kMinContactRatio * (l.R[a] + l.R[b])) return std::pair{cell_of(a), cell_of(b)};
  }
  return std::nullopt;
}

// Random packings of the kinds that break numerical code (kind 0–5): cells stacked on one point, the
// mother of a cell on the bud of another, a stack through the Lees–Edwards image, far more cells than
// the box holds, clumps that the reader accepts although far from force balance (every overlap up
// to just under half its contact distance), a loose gas.
Packing degenerate_packing(int kind, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double L = kind == 3 ? 2.4 : 3 + 5 * u(rng);
  Packing p = box_of(L, kind == 2 ? u(rng) - 0.5 : 0);
  const auto n = static_cast<std::size_t>(6 + rng() % 20);
  auto random_cell = [&](double region) {
    p.add_cell(region * u(rng), region * u(rng), 7 * u(rng), 1.1 * u(rng), 0.002, -1);
  };
  if (kind == 0) {  // stacked
    random_cell(L);
    for (std::size_t i = 1; i < n; ++i) p.add_cell(p.x(0), p.y(0), p.theta(0), p.b[0], 0.002, -1);
  } else if (kind == 1) {  // the mother of one cell on the bud of another
    for (std::size_t i = 0; i < n; ++i) random_cell(L);
    Lobes l;
    place_lobes(p, l);
    p.add_cell(l.x[1] + Dumbbell::of(0.3).mother_offset, l.y[1], 0, 0.3, 0.002, -1);
  } else if (kind == 2) {  // stacked through the image one box up
    random_cell(L);
    p.add_cell(p.x(0) + p.box.shear * L, p.y(0) + L, p.theta(0), p.b[0], 0.002, -1);
  } else if (kind == 3) {  // φ far above 4
    for (std::size_t i = 0; i < 40; ++i) random_cell(L);
  } else {  // accepted clumps: overlaps up to just under half the contact distance, or a loose gas
    const double region = kind == 4 ? 1.5 + u(rng) : L;
    for (std::size_t i = 0; i < n; ++i) {
      random_cell(region);
      for (int attempt = 0; attempt < 200 && overlap_problem(p); ++attempt) {
        p.q[3 * i] = region * u(rng);
        p.q[3 * i + 1] = region * u(rng);
      }
      if (overlap_problem(p)) {  // no room left: the clump is full
        p.q.conservativeResize(3 * static_cast<Eigen::Index>(i));
        p.b.pop_back(), p.gamma0.pop_back(), p.id.pop_back(), p.parent.pop_back();
        --p.next_id;
        break;
      }
    }
  }
  return p;
}

void write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST_CASE("the reader refuses coincident lobes of two cells, naming both cells and the later one's line",
          "[degenerate]") {
  Packing p = box_of(8);
  p.add_cell(2, 2, 0, 0.5, 0.002, -1);
  p.add_cell(5, 5, 0, 0.5, 0.002, -1);
  p.add_cell(2, 2, 0, 0.5, 0.002, -1);  // stacked on cell 0
  // Lines: magic, L, shear, N, next_id, cells, then rows 7, 8, 9.
  const std::string e = error_of(p);
  CHECK_THAT(e, Contains("d.pack:9: the mother of cell 0 and the mother of cell 2 are r = 0 apart"));
  CHECK_THAT(e, Contains("not more than half their contact distance sigma = 1"));
  // The bud of one cell on the mother of another.
  Packing q = box_of(8);
  q.add_cell(2, 2, 0, 0.5, 0.002, -1);
  const Dumbbell d = Dumbbell::of(0.5);
  q.add_cell(2 + d.bud_offset + d.mother_offset, 2, 0, 0.5, 0.002, -1);  // its mother where cell 0's bud is
  CHECK_THAT(error_of(q), Contains("the bud of cell 0 and the mother of cell 1 are r = "));
}

TEST_CASE("the overlap rule accepts overlaps below half the contact distance and refuses them from there on",
          "[degenerate]") {
  for (double r : {0.5000001, 0.75, 0.99}) {
    Packing p = box_of(8);
    p.add_cell(3, 3, std::numbers::pi / 2, 0, 0.002, -1);  // b = 0: the mother alone, centred
    p.add_cell(3 + r, 3, std::numbers::pi / 2, 0, 0.002, -1);
    CHECK(error_of(p).empty());
  }
  for (double r : {0.5, 0.3, 1e-300, 0.0}) {
    Packing p = box_of(8);
    p.add_cell(3, 3, std::numbers::pi / 2, 0, 0.002, -1);
    p.add_cell(3 + r, 3, std::numbers::pi / 2, 0, 0.002, -1);
    CHECK_THAT(error_of(p), Contains("d.pack:8: the mother of cell 0 and the mother of cell 1"));
  }
}

TEST_CASE(
    "the overlap rule finds the first violating pair of the O(N^2) oracle, across the periodic and "
    "Lees-Edwards boundaries",
    "[degenerate]") {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0, 1);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double L = 2.6 + 6 * u(rng);
    // Shears beyond ±1/2 give the same lattice as their fractional part: both kinds are tried.
    Packing p = box_of(L, trial % 3 == 0 ? 0 : (u(rng) - 0.5) * (trial % 2 ? 1 : 7));
    const auto n = static_cast<std::size_t>(2 + rng() % 12);
    for (std::size_t i = 0; i < n; ++i)
      p.add_cell(L * (4 * u(rng) - 2), L * (4 * u(rng) - 2), 7 * u(rng), 1.2 * u(rng), 0.002, -1);
    if (trial % 4 == 1) {  // the image of a cell one box up, shifted by γL: the same place
      const std::size_t i = rng() % n;
      p.add_cell(p.x(i) + p.box.shear * L + 1e-3 * u(rng), p.y(i) + L, p.theta(i), p.b[i], 0.002, -1);
    }
    std::pair<std::size_t, std::size_t> cells;
    const auto problem = overlap_problem(p, &cells);
    const auto oracle = brute_force_violation(p);
    INFO("trial " << trial);
    REQUIRE(problem.has_value() == oracle.has_value());
    if (oracle) {
      ++refused;
      CHECK(cells == *oracle);
    }
  }
  CHECK(refused > 50);  // both verdicts were exercised
  CHECK(refused < 250);
}

TEST_CASE("the reader refuses phi >= 4 before looking for pairs: 10^5 cells stacked on one point are refused at once",
          "[degenerate]") {
  Packing p = box_of(2.4);
  for (int i = 0; i < 30; ++i) p.add_cell(1, 1, 0, 0, 0.002, -1);  // φ = 30 π/4 / 2.4² = 4.09
  CHECK_THAT(error_of(p), Contains("d.pack:2: packing fraction phi = 4.09"));
  // A large box of stacked cells has φ < 4: the pair check must stop at the first pair.
  Packing q = box_of(400);
  for (int i = 0; i < 100000; ++i) q.add_cell(1, 1, 0, 0.5, 0.002, -1);
  const auto t0 = std::chrono::steady_clock::now();
  CHECK_THAT(error_of(q), Contains("the mother of cell 0 and the mother of cell 1 are r = 0 apart"));
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 5);
  // A vast box with two cells: no bins for the empty space (the pair check alone; the reader refuses
  // a box beyond the scene's box.L bound before it).
  Packing vast = box_of(1e300);
  vast.add_cell(1, 1, 0, 0.5, 0.002, -1);
  vast.add_cell(1.1, 1, 0, 0.5, 0.002, -1);
  CHECK_THAT(overlap_problem(vast).value_or(""), Contains("the mother of cell 0 and the mother of cell 1 are r = 0.1"));
  CHECK_THAT(error_of(vast), Contains("d.pack:2: box side L = 1e+300 must be at most 10000"));
}

TEST_CASE("packings grown and compressed by budjam obey the geometric rules", "[degenerate]") {
  for (const char* name : {"saddle_jamming_L15_seed3.pack", "shear_conventions_differ_L8.pack"}) {
    const io::PackingFile f = io::read_packing(budjam::testing::source_file(std::string("tests/data/") + name));
    CHECK_FALSE(density_problem(f.packing));
    CHECK_FALSE(overlap_problem(f.packing));
  }
}

// The property the rules serve: every packing the reader accepts gets a finite answer, a notice or a
// refusal from the numerical commands, on the random degenerate packings above.
TEST_CASE(
    "moduli, dos and rigidity on random degenerate packings: finite results, a notice or a refusal; never NaN "
    "with success, never internal, bounded time",
    "[degenerate]") {
  std::mt19937_64 rng(2026);
  int accepted = 0, notices = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const int kind = trial % 6;
    const Packing p = degenerate_packing(kind, rng);
    const std::string file = "deg" + std::to_string(trial) + ".pack";
    write(work_dir() / file, io::format_packing(p));
    for (const std::string command : {"moduli", "dos", "rigidity"}) {
      const auto t0 = std::chrono::steady_clock::now();
      const auto r = budjam::testing::run_budjam_in(work_dir(), command + " " + file + " --json");
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      INFO("trial " << trial << " (kind " << kind << "), budjam " << command << ": exit " << r.code << ", " << r.err);
      CHECK(seconds < 20);
      CHECK(r.err.find("internal") == std::string::npos);
      CHECK(std::count(r.err.begin(), r.err.end(), '\n') <= 1);
      if (kind < 4) CHECK(r.code == 2);  // the reader's rules refuse every one of these
      if (r.code == 2) {
        CHECK(r.err.find("budjam: error: " + file + ":") == 0);
        continue;
      }
      if (r.code == 1) {  // a notice (not an error) saying why there is no answer
        ++notices;
        CHECK(r.err.rfind("budjam: ", 0) == 0);
        CHECK(r.err.find("budjam: error:") == std::string::npos);
        continue;
      }
      REQUIRE(r.code == 0);
      ++accepted;
      const io::Json j = io::Json::parse(r.out);
      if (command == "moduli")
        for (const char* key : {"B", "G", "B_energy", "G_energy", "P"}) CHECK(j[key].is_number());
      if (command == "dos") {
        CHECK(j["lambda_min"].is_number());
        CHECK(j["N_zero"].is_number());
      }
    }
  }
  // The accepted clumps exercised the commands beyond the reader.
  CHECK(accepted + notices > 0);
}
