// The packing file format (io/packing_file.hpp).
#include "budjam/contacts.hpp"
#include "budjam/packing_rules.hpp"
#include "io/packing_file.hpp"
#include "io/run_data.hpp"
#include "random_packing.hpp"
#include "run_budjam.hpp"

#include <catch2/catch.hpp>

#include <unistd.h>
#include <bit>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>

using namespace budjam;
using namespace budjam::io;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

// A finite double with uniformly random bits: every exponent, subnormals, ±0 all occur.
double random_finite(std::mt19937_64& rng) {
  while (true) {
    const double d = std::bit_cast<double>(rng());
    if (std::isfinite(d)) return d;
  }
}

Packing random_packing(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing p;
  p.box.L = 15.0 + u(rng);
  p.box.shear = 1e-7 * u(rng);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t parent = i < 2 ? -1 : static_cast<std::int64_t>(rng() % i);
    p.add_cell(p.box.L * u(rng), p.box.L * u(rng), 2 * std::numbers::pi * (u(rng) - 0.5), 0.01 + u(rng),
               0.002 * (0.8 + 0.4 * u(rng)), parent);
  }
  testing::redraw_refused_overlaps(p, [&](std::size_t i) {
    p.q[3 * i] = p.box.L * u(rng);
    p.q[3 * i + 1] = p.box.L * u(rng);
  });
  return p;
}

void require_identical(const Packing& a, const Packing& b) {
  REQUIRE(a.size() == b.size());
  CHECK(same_bits(a.box.L, b.box.L));
  CHECK(same_bits(a.box.shear, b.box.shear));
  CHECK(a.next_id == b.next_id);
  CHECK(a.id == b.id);
  CHECK(a.parent == b.parent);
  REQUIRE(a.q.size() == b.q.size());
  for (Eigen::Index k = 0; k < a.q.size(); ++k) REQUIRE(same_bits(a.q[k], b.q[k]));
  for (std::size_t i = 0; i < a.size(); ++i) {
    REQUIRE(same_bits(a.b[i], b.b[i]));
    REQUIRE(same_bits(a.gamma0[i], b.gamma0[i]));
  }
}

std::string error_of(const std::string& text) {
  try {
    parse_packing(text, "t.pack");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  return s.replace(at, from.size(), to);
}

// Line numbers: 1 magic, 2 L, 3 shear, 4 N, 5 next_id, 6 meta phase, 7 cells, 8–10 rows, 11 end.
const std::string kValid =
    "budjam-packing 1\n"
    "L 8\n"
    "shear 0\n"
    "N 3\n"
    "next_id 3\n"
    "meta phase jammed\n"
    "cells id parent x y theta b gamma0\n"
    "0 -1 4 3.5 0.25 0.5 0.002\n"
    "1 -1 4 4.5 -1 0.7245 0.0021\n"
    "2 0 5 4 3 0.01 0.0019\n"
    "end\n";

}  // namespace

TEST_CASE("a packing file round-trips every double bit-exactly, including extreme values", "[packing_file]") {
  std::mt19937_64 rng(7);
  Packing p = random_packing(200, 11);
  // Coordinates and angles with arbitrary bit patterns (the format must not care what they mean),
  // positions within the physical bound of kMaxBoxesAway boxes.
  for (Eigen::Index k = 0; k < p.q.size(); ++k) {
    do p.q[k] = random_finite(rng);
    while (k % 3 != 2 && !(std::abs(p.q[k]) <= kMaxBoxesAway * p.box.L));
  }
  p.q[0] = -0.0;
  p.q[1] = std::numeric_limits<double>::denorm_min();
  p.q[2] = std::numeric_limits<double>::max();
  p.q[3] = -std::numeric_limits<double>::min();
  p.b[0] = 0.0;
  p.b[1] = std::nextafter(0.01, 1.0);
  p.gamma0[2] = 0.1 + 0.2;
  testing::redraw_refused_overlaps(p, [&](std::size_t i) {
    for (int c = 0; c < 2; ++c) do
        p.q[3 * i + c] = random_finite(rng);
      while (!(std::abs(p.q[3 * i + c]) <= kMaxBoxesAway * p.box.L));
  });
  PackingMeta meta;
  meta.set("phase", "target");
  meta.set_number("phi", 0.8412345678901234);
  meta.set_number("P", 1.234e-5);
  meta.set_integer("step", 123456789012);
  meta.set("note", " spaced  value with, commas ");
  meta.set("empty", "");

  const std::string text = format_packing(p, meta);
  const PackingFile r = parse_packing(text, "mem.pack");
  require_identical(p, r.packing);
  CHECK(r.meta.values == meta.values);
  CHECK(same_bits(r.meta.number("phi"), 0.8412345678901234));
  CHECK(r.meta.integer("step") == 123456789012);
  CHECK(format_packing(r.packing, r.meta) == text);  // a fixed point after one cycle
}

TEST_CASE("write_packing and read_packing round-trip through a file", "[packing_file]") {
  const auto dir = std::filesystem::temp_directory_path() / ("budjam-pack-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Packing p = random_packing(50, 3);
  PackingMeta meta;
  meta.set("phase", "jammed");
  write_packing(dir / "packings" / "jammed.pack", p, meta);
  const PackingFile r = read_packing(dir / "packings" / "jammed.pack");
  require_identical(p, r.packing);
  CHECK(r.meta.get("phase") == "jammed");
  CHECK_THROWS_WITH(read_packing(dir / "missing.pack"), Contains("missing.pack: cannot read"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("the reference example of the format is read as documented", "[packing_file]") {
  const PackingFile f = parse_packing(kValid, "t.pack");
  const Packing& p = f.packing;
  REQUIRE(p.size() == 3);
  CHECK(p.box.L == 8);
  CHECK(p.next_id == 3);
  CHECK(p.x(1) == 4);
  CHECK(p.y(1) == 4.5);
  CHECK(p.theta(1) == -1);
  CHECK(p.b[1] == 0.7245);
  CHECK(p.gamma0[2] == 0.0019);
  CHECK(p.parent[2] == 0);
  CHECK(f.meta.get("phase") == "jammed");
  // Comments and blank lines are allowed in the header; CRLF line ends are tolerated.
  CHECK(parse_packing(replace(kValid, "L 8\n", "# a comment\n\nL 8\n"), "t").packing.size() == 3);
  std::string crlf;
  for (char c : kValid) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  require_identical(parse_packing(crlf, "t").packing, p);
}

TEST_CASE("each kind of corrupt packing file is refused with its line number", "[packing_file]") {
  struct Case {
    std::string text, message;
  };
  const std::vector<Case> cases = {
      {"", "t.pack:1: empty file"},
      {replace(kValid, "budjam-packing 1", "budjam-pack 1"), "t.pack:1: not a budjam packing file"},
      {replace(kValid, "budjam-packing 1", "x,y,z"), "t.pack:1: not a budjam packing file"},
      {replace(kValid, "budjam-packing 1", "budjam-packing 2"), "t.pack:1: unsupported packing format version 2"},
      {replace(kValid, "budjam-packing 1", "budjam-packing one"), "t.pack:1: format version is not an integer"},
      {replace(kValid, "N 3\n", ""), "t.pack:6: the header lacks \"N\""},
      {replace(kValid, "L 8\n", ""), "t.pack:6: the header lacks \"L\""},
      {replace(kValid, "N 3\n", "N 3\nN 3\n"), "t.pack:5: duplicate header key \"N\""},
      {replace(kValid, "shear 0\n", "shear 0\ncolour blue\n"), "t.pack:4: unknown header key \"colour\""},
      {replace(kValid, "L 8", "L eight"), "t.pack:2: L: not a number (got \"eight\")"},
      {replace(kValid, "L 8", "L 0"), "t.pack:2: L: must be positive"},
      {replace(kValid, "L 8", "L inf"), "t.pack:2: L: not finite"},
      {replace(kValid, "N 3", "N -3"), "t.pack:4: N: must not be negative"},
      {replace(kValid, "N 3", "N 3.5"), "t.pack:4: N: not an integer"},
      {replace(kValid, "meta phase jammed", "meta ph@se jammed"), "t.pack:6: invalid meta key"},
      {replace(kValid, "cells id parent x y theta b gamma0", "cells id x y"), "t.pack:7: the cells line must be"},
      {replace(kValid, "4 4.5 -1 0.7245", "4 4.5 0.7245"),
       "t.pack:9: expected 7 columns (id parent x y theta b gamma0), found 6"},
      {replace(kValid, "0.0021\n", "0.0021 9\n"), "t.pack:9: expected 7 columns"},
      {replace(kValid, "4 4.5 -1", "4 abc -1"), "t.pack:9: column y: not a number (got \"abc\")"},
      {replace(kValid, "4 4.5 -1", "4 4.5x -1"), "t.pack:9: column y: not a number (got \"4.5x\")"},
      {replace(kValid, "4 4.5 -1", "4 nan -1"), "t.pack:9: column y: not finite (got nan)"},
      {replace(kValid, "4 4.5 -1", "4 4.5 -inf"), "t.pack:9: column theta: not finite (got -inf)"},
      {replace(kValid, "2 0 5 4 3", "2 0.5 5 4 3"), "t.pack:10: column parent: not an integer"},
      {replace(kValid, "1 -1 4 4.5", "0 -1 4 4.5"), "t.pack:9: duplicate id 0 (first on line 8)"},
      {replace(kValid, "2 0 5 4 3", "7 0 5 4 3"), "t.pack:10: column id: must lie in [0, next_id = 3) (got 7)"},
      {replace(kValid, "2 0 5 4 3", "2 2 5 4 3"), "t.pack:10: column parent: must be -1 or another id"},
      {replace(kValid, "0.01 0.0019", "-0.01 0.0019"), "t.pack:10: column b: must not be negative"},
      {replace(kValid, "0.01 0.0019", "0.01 -0.0019"), "t.pack:10: column gamma0: must not be negative"},
      {replace(kValid, "N 3", "N 4"), "t.pack:11: expected N = 4 cell rows, found 3"},
      {replace(kValid, "N 3", "N 2"), "t.pack:10: more cell rows than N = 2"},
      {replace(kValid, "end\n", ""), "t.pack:11: truncated: missing the \"end\" line"},
      {replace(kValid, "2 0 5 4 3 0.01 0.0019\nend\n", ""),
       "t.pack:10: truncated: expected N = 3 cell rows, the file ends after 2"},
      {replace(kValid, "end\n", "end\n0 -1 1 1 1 1 1\n"), "t.pack:12: unexpected text after \"end\""},
      {"budjam-packing 1\nL 8\nshear 0\n", "t.pack:4: truncated: the header has no \"cells\" line"},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    const std::string message = error_of(c.text);
    CHECK_THAT(message, StartsWith(c.message));
    CHECK(message.find('\n') == std::string::npos);
  }
}

TEST_CASE("every truncation of a packing file is refused", "[packing_file]") {
  // Files are written atomically, but a copy can still be cut short; no prefix of a file may
  // read as a valid packing (the only exception: the final newline alone).
  Packing p = random_packing(6, 5);
  PackingMeta meta;
  meta.set_number("phi", 0.5);
  const std::string text = format_packing(p, meta);
  for (std::size_t n = 0; n + 1 < text.size(); ++n) {
    INFO("prefix of " << n << " bytes");
    CHECK_THAT(error_of(text.substr(0, n)), StartsWith("t.pack:"));
  }
  CHECK(error_of(text.substr(0, text.size() - 1)).empty());
}

TEST_CASE("a corrupt header N cannot make the reader allocate for cells that are not there", "[packing_file]") {
  CHECK_THAT(error_of(replace(kValid, "N 3", "N 9000000000000000000")), StartsWith("t.pack:11: expected N ="));
}

TEST_CASE("format_packing refuses packings that could not be read back", "[packing_file]") {
  Packing p = random_packing(3, 1);
  p.q[4] = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(format_packing(p), std::invalid_argument);
  p = random_packing(3, 1);
  p.id[2] = p.id[1];
  CHECK_THROWS_AS(format_packing(p), std::invalid_argument);
  p = random_packing(3, 1);
  p.b.pop_back();
  CHECK_THROWS_AS(format_packing(p), std::invalid_argument);
  PackingMeta meta;
  CHECK_THROWS_AS(meta.set("two words", "x"), std::invalid_argument);
  CHECK_THROWS_AS(meta.set("k", "line\nbreak"), std::invalid_argument);
  meta.set("phi", "not a number");
  CHECK_THROWS_WITH(meta.number("phi"), "meta.phi: not a number (got \"not a number\")");
  CHECK_THROWS_WITH(meta.number("P"), "meta.P: missing");
}

TEST_CASE("a packing that breaks a physical rule is refused naming the line", "[packing_file]") {
  const std::vector<std::pair<std::string, std::string>> cases{
      {replace(kValid, "L 8\n", "L 1e-300\n"), "t.pack:2: box side L = 1e-300 must exceed"},
      {replace(kValid, "L 8\n", "L 1e39\n"), "t.pack:2: box side L = 1e+39 must be at most 10000"},
      {replace(kValid, "L 8\n", "L 10000.5\n"), "t.pack:2: box side L = 10000.5 must be at most 10000"},
      {replace(kValid, "L 8\n", "L 2.25\n"),
       "t.pack:2: box side L = 2.25 must exceed 2 (largest lobe diameter + skin) = 2.3"},
      {replace(kValid, "shear 0\n", "shear 1e308\n"),
       "t.pack:2: box shear = 1e+308 must be finite and at most 16 in size"},
      {replace(kValid, "0 -1 4 3.5", "0 -1 136.5 3.5"), "t.pack:8: cell 0: position more than 16 box sides"},
      {replace(kValid, "0 -1 4 3.5", "0 -1 1e300 3.5"), "t.pack:8: cell 0: position more than"},
      {replace(kValid, "0.25 0.5 0.002", "0.25 1e300 0.002"),
       "t.pack:8: cell 0: bud diameter b = 1e+300 outside [0, 3]"},
      {replace(kValid, "0.25 0.5 0.002", "0.25 3.5 0.002"), "t.pack:8: cell 0: bud diameter b = 3.5 outside"},
  };
  for (const auto& [text, message] : cases) CHECK_THROWS_WITH(parse_packing(text, "t.pack"), Contains(message));
}

TEST_CASE("the box side L is bounded by the scene's box.L bound, so positions stay within every export's range",
          "[packing_file]") {
  CHECK(parse_packing(replace(kValid, "L 8\n", "L 10000\n"), "t.pack").packing.box.L == 10000);
  CHECK_THROWS_WITH(parse_packing(replace(kValid, "L 8\n", "L 1e300\n"), "t.pack"),
                    "t.pack:2: box side L = 1e+300 must be at most 10000 (the largest box.L of a scene)");
}

TEST_CASE("a meta value that is not UTF-8 is refused naming the line, as one a file cannot hold", "[packing_file]") {
  CHECK_THROWS_WITH(parse_packing(replace(kValid, "meta phase jammed", "meta phase t\xe9rget"), "t.pack"),
                    StartsWith("t.pack:6: meta phase: the value is not valid UTF-8 (byte 2 of the value"));
  CHECK(parse_packing(replace(kValid, "meta phase jammed", "meta phase t\xc3\xa9rget"), "t.pack")
            .meta.values.at("phase") == "t\xc3\xa9rget");
  PackingMeta meta;
  CHECK_THROWS_AS(meta.set("k", "t\xe9"), std::invalid_argument);
  meta.values["k"] = "t\xe9";
  CHECK(unwritable_problem(random_packing(3, 1), meta) == "meta[\"k\"]: the value is not valid UTF-8");
}

TEST_CASE(
    "a packing file with a UTF-8 byte-order mark is refused saying so, also where validate tells packings "
    "from scenes",
    "[packing_file]") {
  const std::string bom = "\xEF\xBB\xBF" + kValid;
  CHECK(looks_like_packing(bom));
  CHECK_THROWS_WITH(parse_packing(bom, "t.pack"), StartsWith("t.pack:1: the file starts with a UTF-8 byte-order mark"));
}

TEST_CASE("unwritable_problem names the quantity as Packing(...) names its arguments", "[packing_file]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto problem = [](auto change) {
    Packing p = random_packing(3, 1);
    change(p);
    return unwritable_problem(p, {}).value_or("");
  };
  CHECK(problem([](Packing& p) { p.box.L = 0; }) == "L: must be finite and > 0 (got 0)");
  CHECK(problem([&](Packing& p) { p.box.L = nan; }) == "L: must be finite and > 0 (got nan)");
  CHECK(problem([&](Packing& p) { p.box.shear = nan; }) == "shear: must be finite (got nan)");
  CHECK(problem([&](Packing& p) { p.q[3] = nan; }) == "x[1]: not finite (got nan)");
  CHECK(problem([&](Packing& p) { p.q[8] = nan; }) == "theta[2]: not finite (got nan)");
  CHECK(problem([](Packing& p) { p.b[0] = -0.5; }) == "b[0]: must be >= 0 (got -0.5)");
  CHECK(problem([&](Packing& p) { p.gamma0[1] = nan; }) == "gamma0[1]: not finite (got nan)");
  CHECK(problem([](Packing&) {}).empty());
}

TEST_CASE("a packing shifted by whole periods up to the bound keeps its contacts and forces; beyond it is refused",
          "[packing_file]") {
  // Periodicity: the physics is the same whatever image of the box a cell's coordinates name. Up to
  // kMaxBoxesAway boxes out the coordinates lose at most 4 bits, so the contact network is the same and
  // the pressure agrees to rounding; farther out the reader refuses instead of reading lost digits.
  // its centroids brought into [0, L) first (whole periods, exact to rounding), so k periods out is k boxes out
  Packing p = read_packing(budjam::testing::source_file("tests/data/negative_G_target_L8.pack")).packing;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int c = 0; c < 2; ++c) p.q[3 * i + c] -= std::floor(p.q[3 * i + c] / p.box.L) * p.box.L;
  const auto at = [&](double k) {
    Packing q = p;
    for (std::size_t i = 0; i < q.size(); ++i) {
      q.q[3 * i] += k * q.box.L;
      q.q[3 * i + 1] -= k * q.box.L;
    }
    return q;
  };
  const tools::PackingContacts base = tools::analyse_contacts(p);
  REQUIRE(base.contacts.size() > 0);
  for (const double k : {1.0, 7.0, kMaxBoxesAway - 1.0}) {
    const Packing q = at(k);
    const PackingFile back = parse_packing(format_packing(q, {}), "shifted.pack");
    const tools::PackingContacts shifted = tools::analyse_contacts(back.packing);
    CHECK(shifted.contacts.size() == base.contacts.size());
    CHECK(shifted.network.Z == base.network.Z);
    CHECK(pressure(shifted.contacts, q.box) == Approx(pressure(base.contacts, p.box)).epsilon(1e-9));
  }
  CHECK_THROWS_WITH(parse_packing(format_packing(at(kMaxBoxesAway + 1.0), {}), "far.pack"),
                    Contains("position more than 16 box sides from the origin"));
}
