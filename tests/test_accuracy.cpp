// `budjam accuracy --packings`: the post-processing knobs (moduli linear solver, ARPACK tol and ncv)
// measured against dense references on the same packings, and the front verdict.
#include "budjam/fire.hpp"
#include "compressed_packing.hpp"
#include "random_packing.hpp"

#include "analysis/accuracy_sweep.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <sys/wait.h>
#include <catch2/catch.hpp>
#include "files_doc.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

using namespace budjam;
using budjam::testing::compress_to_pressure;
using budjam::testing::CompressionResult;
using budjam::testing::random_dumbbells;
namespace fs = std::filesystem;
using budjam::testing::run_budjam;
using budjam::testing::shell_quoted;
using budjam::testing::source_file;
using budjam::testing::work_dir;

namespace {

// Two small compressed packings in <dir>/<k>/packings/, as a growth run stores them.
fs::path packing_set() {
  const fs::path dir = work_dir() / "set";
  FireParams fire;
  fire.dt_max = 0.4;
  fire.force_tol = 1e-14;
  for (std::uint64_t seed : {1, 2}) {
    const CompressionResult c = compress_to_pressure(random_dumbbells(70, 0.4, 0.01, 1.02, seed), 1e-3, fire);
    REQUIRE(c.converged);
    fs::create_directories(dir / std::to_string(seed) / "packings");
    io::write_packing(dir / std::to_string(seed) / "packings" / "target_0.pack", c.packing);
  }
  return dir;
}

const io::Json* row(const io::Json& acc, const std::string& family, const std::string& variant) {
  for (const auto& r : acc["rows"])
    if (r["family"] == family && r["variant"] == variant) return &r;
  return nullptr;
}

}  // namespace

TEST_CASE("budjam accuracy --packings: every solver and ARPACK setting against dense references, with a front verdict",
          "[fast]") {
  const fs::path set = packing_set();
  const fs::path out = work_dir() / "acc";
  REQUIRE(run_budjam("accuracy --packings 'small=" + set.string() + "' --min-seconds 0 --out '" + out.string() + "'")
              .code == 0);
  const io::Json acc = io::read_json(out / "accuracy.json");
  CHECK(acc.value("format", "") == "budjam-accuracy");  // how a later --out recognises its own output
  CHECK(testing::csv_header(out / "accuracy.csv") == testing::documented_columns("`DIR/accuracy.csv`"));

  // Direct solvers agree with the dense reference at rounding level; CG to its tolerance (relative to
  // B; G relative to itself can be larger when G ≪ B).
  for (const std::string v :
       {"ldlt", "ldlt refine=0", "ldlt refine_above=1e-15", "cholesky", "cholesky refine_above=1e-15"}) {
    const io::Json* r = row(acc, "moduli", v);
    REQUIRE(r != nullptr);
    INFO(v);
    CHECK((*r)["n"].get<int>() == 2);
    CHECK((*r)["err_B"].get<double>() < 1e-10);
    CHECK((*r)["max_err_G"].get<double>() < 1e-8);
    CHECK((*r)["well_posed"].get<bool>());
    CHECK((*r)["seconds"].get<double>() > 0);
  }
  const io::Json* cg = row(acc, "moduli", "cg-ichol tol=1e-4");
  REQUIRE(cg != nullptr);
  CHECK((*cg)["max_err_B"].get<double>() < 1e-3);
  CHECK((*cg)["max_residual"].get<double>() <= 1e-3);
  CHECK((*cg)["err_B"].get<double>() > (*row(acc, "moduli", "cg-ichol tol=1e-10"))["err_B"].get<double>());
  CHECK((*row(acc, "moduli", "dense"))["reference"].get<bool>());
  CHECK((*row(acc, "moduli", "dense"))["err_B"].is_null());

  // ARPACK at its default reproduces the dense ω* and band eigenvalues; every setting was computed.
  const io::Json* arpack = row(acc, "spectrum", "arpack tol=1e-10 ncv=auto");
  REQUIRE(arpack != nullptr);
  CHECK((*arpack)["default"].get<bool>());
  CHECK((*arpack)["err_omega_star"].get<double>() < 1e-9);
  CHECK((*arpack)["max_err_band"].get<double>() < 1e-9);
  for (const auto& r : acc["rows"])
    if (r["family"] == "spectrum") CHECK(r["failures"].get<int>() == 0);

  // One group per knob, the default first; the verdict is consistent with the dominance lists.
  std::set<std::string> knobs;
  bool all = true;
  for (const auto& g : acc["groups"]) {
    knobs.insert(g["knob"].get<std::string>());
    CHECK(g["variants"][0] == g["default"]);
    CHECK(g["default_on_front"].get<bool>() == g["default_dominated_by"].empty());
    all = all && g["default_on_front"].get<bool>();
  }
  CHECK(knobs == std::set<std::string>{"solver", "arpack_tol", "arpack_ncv"});
  CHECK(acc["defaults_on_front"].get<bool>() == all);
  CHECK(fs::exists(out / "accuracy.csv"));
  CHECK(fs::exists(out / "accuracy.md"));
}

TEST_CASE("budjam accuracy refuses incomplete or malformed requests with exit code 2", "[fast]") {
  const fs::path out = work_dir() / "bad";
  CHECK(run_budjam("accuracy --out '" + out.string() + "'").code == 2);  // nothing to measure
  CHECK(run_budjam("accuracy --packings 'x=" + (work_dir() / "missing").string() + "' --out '" + out.string() + "'")
            .code == 2);
  CHECK(run_budjam("accuracy --packings nodir --out '" + out.string() + "'").code == 2);
  CHECK(run_budjam("accuracy --reference '" + work_dir().string() + "' --out '" + out.string() + "'").code == 2);
  CHECK(run_budjam("accuracy --packings 'a,b=" + work_dir().string() + "' --out '" + out.string() + "'").code == 2);
}

TEST_CASE("a knob measured on two packing sets is judged on its joint front: geometric-mean relative cost, worst error",
          "[fast]") {
  const fs::path set = packing_set();
  const fs::path out = work_dir() / "acc_joint";
  REQUIRE(run_budjam("accuracy --packings 'a=" + (set / "1").string() + "' --packings 'b=" + (set / "2").string() +
                     "' --min-seconds 0 --out '" + out.string() + "'")
              .code == 0);
  const io::Json acc = io::read_json(out / "accuracy.json");
  auto cost = [&](const std::string& set_name, const std::string& family, const std::string& variant) {
    for (const auto& r : acc["rows"])
      if (r["set"] == set_name && r["family"] == family && r["variant"] == variant) return r["cost"].get<double>();
    FAIL("no row " << set_name << " " << variant);
    return 0.0;
  };
  auto default_of = [&](const std::string& set_name, const std::string& family) {
    for (const auto& r : acc["rows"])
      if (r["set"] == set_name && r["family"] == family && r["default"].get<bool>())
        return r["variant"].get<std::string>();
    FAIL("no default");
    return std::string();
  };
  std::set<std::string> knobs;
  bool all = true;
  for (const auto& j : acc["joint_groups"]) {
    knobs.insert(j["knob"].get<std::string>());
    CHECK(j["sets"] == io::Json::array({"a", "b"}));
    const std::string family = j["family"].get<std::string>();
    for (const auto& s : j["settings"]) {
      const std::string name = s["setting"].get<std::string>();
      const std::string v = name == "default" ? default_of("a", family) : name;
      const double expect = std::sqrt(cost("a", family, v) / cost("a", family, default_of("a", family)) *
                                      cost("b", family, v) / cost("b", family, default_of("b", family)));
      CHECK(s["relative_cost"].get<double>() == Approx(expect).epsilon(1e-12));
    }
    CHECK(j["settings"][0]["setting"] == "default");
    CHECK(j["default_on_front"].get<bool>() == j["default_dominated_by"].empty());
    all = all && j["default_on_front"].get<bool>();
  }
  CHECK(knobs == std::set<std::string>{"solver", "arpack_tol", "arpack_ncv"});
  // With every knob measured on both sets, the verdict is that of the joint fronts alone.
  CHECK(acc["defaults_on_front"].get<bool>() == all);
}

namespace {

// Copies every seed of `from` to `to`, adding shift[k] to φ_2 of the k-th seed's summary.json.
void copy_with_phi2_shift(const fs::path& from, const fs::path& to, const std::vector<double>& shift) {
  for (std::size_t k = 0; k < shift.size(); ++k) {
    const std::string seed = "seed" + std::to_string(k + 1);
    fs::create_directories(to);
    fs::copy(from / seed, to / seed, fs::copy_options::recursive);
    io::Json s = io::read_json(to / seed / "summary.json");
    s["phi_2"] = s["phi_2"].get<double>() + shift[k];
    io::write_json(to / seed / "summary.json", s);
  }
}

}  // namespace

TEST_CASE(
    "phi_2 is judged over the seeds: one switched branch is within its resolution (a tie), a shift of every seed is "
    "resolved; from fewer than 5 seeds it has no resolution and is not judged",
    "[fast]") {
  const fs::path dir = work_dir() / "acc_phi2";
  const fs::path ref = dir / "reference";
  for (int seed = 1; seed <= 5; ++seed)
    REQUIRE(run_budjam("grow " + shell_quoted(source_file("data/scenes/demo.toml")) + " --quiet --seed " +
                       std::to_string(seed) + " --out " + shell_quoted(ref / ("seed" + std::to_string(seed))) +
                       " --set box.L=6 --set 'jamming.targets=[1e-3]' --set jamming.continue_to_phi2=true")
                .code == 0);
  copy_with_phi2_shift(ref, dir / "default", {0, 0, 0, 0, 0});
  copy_with_phi2_shift(ref, dir / "ftol_1e-11", {0, 0, 0, 0, 0.01});                // one seed on another branch
  copy_with_phi2_shift(ref, dir / "ftol_1e-10", {0.01, 0.011, 0.009, 0.01, 0.01});  // every seed moved alike
  REQUIRE(run_budjam("accuracy --reference " + shell_quoted(ref) + " " + shell_quoted(dir / "default") + " " +
                     shell_quoted(dir / "ftol_1e-11") + " " + shell_quoted(dir / "ftol_1e-10") + " --out " +
                     shell_quoted(dir / "out"))
              .code == 0);
  const io::Json acc = io::read_json(dir / "out" / "accuracy.json");
  const io::Json* one = row(acc, "growth", "ftol_1e-11");
  const io::Json* all = row(acc, "growth", "ftol_1e-10");
  const io::Json* def = row(acc, "growth", "default");
  REQUIRE(one);
  REQUIRE(all);
  REQUIRE(def);
  // |mean| of the signed differences, and 2 standard errors of that mean
  CHECK((*one)["err_phi_2"].get<double>() == Approx(0.01 / 5).epsilon(1e-9));
  CHECK((*one)["res_phi_2"].get<double>() == Approx(2 * 0.002).epsilon(1e-9));  // SD 0.01/√5, SE 0.002
  CHECK((*all)["err_phi_2"].get<double>() == Approx(0.01).epsilon(1e-9));
  CHECK((*all)["res_phi_2"].get<double>() == Approx(2 * std::sqrt(5e-7 / 5)).epsilon(1e-9));
  CHECK((*def)["err_phi_2"].get<double>() == 0.0);
  // Same runs, same cost: the switched branch ties with the default; the resolved shift is worse.
  const auto front_of = [&](const std::string& knob) {
    for (const auto& g : acc["groups"])
      if (g["knob"] == knob) return g["front_by_quantity"]["phi_2"];
    FAIL("no group " << knob);
    return io::Json();
  };
  const io::Json front = front_of("ftol");
  std::set<std::string> names;
  for (const auto& n : front) names.insert(n.get<std::string>());
  CHECK(names == std::set<std::string>{"default", "ftol_1e-11"});
  CHECK(acc["defaults_on_front"].get<bool>());
  // The CSV carries the resolution column that docs/columns.md documents.
  std::ifstream csv(dir / "out" / "accuracy.csv");
  std::string head;
  std::getline(csv, head);
  CHECK(head.find(",res_phi_2,") != std::string::npos);

  // The same variants on three seeds: no resolution from fewer than 5, and φ_2 is not judged — the
  // shift of every seed no longer puts ftol_1e-10 off the φ_2 front, and the table says why.
  const fs::path three = dir / "three";
  for (const char* v : {"reference", "default", "ftol_1e-11", "ftol_1e-10"}) {
    fs::create_directories(three / v);
    for (int seed = 1; seed <= 3; ++seed)
      fs::copy(dir / v / ("seed" + std::to_string(seed)), three / v / ("seed" + std::to_string(seed)),
               fs::copy_options::recursive);
  }
  REQUIRE(run_budjam("accuracy --reference " + shell_quoted(three / "reference") + " " +
                     shell_quoted(three / "default") + " " + shell_quoted(three / "ftol_1e-11") + " " +
                     shell_quoted(three / "ftol_1e-10") + " --out " + shell_quoted(three / "out"))
              .code == 0);
  const io::Json acc3 = io::read_json(three / "out" / "accuracy.json");
  const io::Json* all3 = row(acc3, "growth", "ftol_1e-10");
  REQUIRE(all3);
  CHECK((*all3)["err_phi_2"].get<double>() == Approx(0.01).epsilon(1e-9));
  CHECK((!all3->contains("res_phi_2") || (*all3)["res_phi_2"].is_null()));
  std::set<std::string> names3;
  for (const auto& g : acc3["groups"])
    if (g["knob"] == "ftol")
      for (const auto& n : g["front_by_quantity"]["phi_2"]) names3.insert(n.get<std::string>());
  CHECK(names3 == std::set<std::string>{"default", "ftol_1e-11", "ftol_1e-10"});
  std::ifstream md(three / "out" / "accuracy.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  CHECK(text.find("3 seeds < 5: not judged") != std::string::npos);
  CHECK(text.find(" ± ") == std::string::npos);
}

TEST_CASE("every growth variant of Makefile.analysis names a knob the sweep knows; another is refused by name",
          "[fast]") {
  const fs::path dir = work_dir() / "acc_knobs";
  const fs::path ref = dir / "reference";
  REQUIRE(run_budjam("grow " + shell_quoted(source_file("data/scenes/demo.toml")) + " --quiet --seed 1 --out " +
                     shell_quoted(ref / "seed1") + " --set box.L=6")
              .code == 0);
  // Each variant is a line "<name>|<overrides>" after ACC_VARIANTS, the reference the last.
  std::ifstream makefile(source_file("Makefile.analysis"));
  std::string line, dirs;
  bool in_variants = false;
  int variants = 0;
  while (std::getline(makefile, line)) {
    if (line.rfind("ACC_VARIANTS", 0) == 0)
      in_variants = true;
    else if (in_variants && line.find('|') != std::string::npos) {
      const std::string name = line.substr(line.find_first_not_of(' '), line.find('|') - line.find_first_not_of(' '));
      if (name == "reference") break;
      fs::create_directories(dir / name);
      fs::copy(ref / "seed1", dir / name / "seed1", fs::copy_options::recursive);
      dirs += ' ';
      dirs += shell_quoted(dir / name);
      ++variants;
    }
  }
  REQUIRE(variants > 20);
  CHECK(run_budjam("accuracy --reference " + shell_quoted(ref) + dirs + " --out " + shell_quoted(dir / "out")).code ==
        0);
  fs::create_directories(dir / "skin_0.3");
  fs::copy(ref / "seed1", dir / "skin_0.3" / "seed1", fs::copy_options::recursive);
  const auto refused = run_budjam("accuracy --reference " + shell_quoted(ref) + " " + shell_quoted(dir / "default") +
                                  " " + shell_quoted(dir / "skin_0.3") + " --out " + shell_quoted(dir / "out2"));
  CHECK(refused.code != 0);
  CHECK(refused.err.find("skin_0.3") != std::string::npos);
  CHECK(refused.err.find("floor") != std::string::npos);
  CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
}

TEST_CASE("the growth cost rates are the least-squares CPU per force evaluation and per factorisation", "[fast]") {
  const auto run = [](double evaluations, double factorisations, double seconds, std::size_t n = 3) {
    tools::SweepRow r;
    r.family = "growth";
    r.force_evaluations = evaluations;
    r.newton_factorisations = factorisations;
    r.seconds = seconds;
    r.n = n;
    return r;
  };
  // CPU = 2 µs per evaluation + 3 ms per factorisation, exactly: the fit recovers both.
  const std::vector<tools::SweepRow> mixed{run(1e5, 10, 0.23), run(2e5, 0, 0.4), run(1.2e5, 4e4, 120.24),
                                           run(3e5, 2e3, 6.6)};
  const tools::GrowthCostRates rates = tools::growth_cost_rates(mixed);
  CHECK(rates.per_evaluation == Approx(2e-6).epsilon(1e-9));
  CHECK(rates.per_factorisation == Approx(3e-3).epsilon(1e-9));
  // No factorisations anywhere: the evaluations carry the whole CPU time (the n-weighted fit).
  const std::vector<tools::SweepRow> fire_only{run(1e5, 0, 0.2, 2), run(2e5, 0, 0.5, 1)};
  const tools::GrowthCostRates fire = tools::growth_cost_rates(fire_only);
  CHECK(fire.per_factorisation == 0.0);
  CHECK(fire.per_evaluation == Approx((2 * 1e5 * 0.2 + 2e5 * 0.5) / (2 * 1e10 + 4e10)).epsilon(1e-12));
  // A fit that would make factorisations free of cost (or negative) falls back to evaluations alone.
  const std::vector<tools::SweepRow> cheap{run(1e5, 1e3, 0.2), run(2e5, 0, 0.5)};
  CHECK(tools::growth_cost_rates(cheap).per_factorisation == 0.0);
}
