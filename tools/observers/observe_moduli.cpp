// Observer "moduli": the non-affine elastic response along a growth run, written to
// <run_dir>/moduli.csv, only when the scene asks ([observe.moduli]: at_jamming, at_phi2,
// at_targets, every k accepted steps above jamming). One row per (state, reason); a state that is
// several things at once (e.g. a target on an `every` step) is computed once. A saddle (kernel_method
// "unstable") is logged with its unstable_modes and empty relaxed moduli. docs/moduli.md.
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "budjam/moduli.hpp"
#include "io/atomic_file.hpp"
#include "io/run_directory.hpp"

#include <cmath>
#include <istream>
#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace budjam::tools::moduli_observer {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kColumns{"event",
                                        "step",
                                        "phi",
                                        "dphi",
                                        "N",
                                        "N_nr",
                                        "N_f",
                                        "N_u",
                                        "N_u_buds",
                                        "contacts",
                                        "Z",
                                        "Z_iso",
                                        "dZ",
                                        "P",
                                        "P_energy",
                                        "B",
                                        "G_simple",
                                        "G_pure",
                                        "G_mean",
                                        "B_affine",
                                        "G_simple_affine",
                                        "G_pure_affine",
                                        "B_energy",
                                        "G_energy_simple",
                                        "G_energy_pure",
                                        "G_energy",
                                        "G_min",
                                        "shear_stable",
                                        "G_min_stress",
                                        "C_xxxx",
                                        "C_yyyy",
                                        "C_xxyy",
                                        "C_xyxy",
                                        "C_xxxy",
                                        "C_yyxy",
                                        "n",
                                        "n_J",
                                        "ell_c",
                                        "M4",
                                        "B_ext",
                                        "G_mf",
                                        "B_ext_nJ",
                                        "G_mf_nJ",
                                        "kernel_method",
                                        "pinned_translation",
                                        "pinned_lobe_rotation",
                                        "pinned_zero_rows",
                                        "residual",
                                        "kernel_component",
                                        "well_posed",
                                        "unstable_modes"};

class ModuliLog : public tools::CsvLogObserver {
 public:
  ModuliLog(const Scene& scene, const io::Directory& dir, bool resuming)
      : CsvLogObserver(dir, {{std::string(io::run_files::moduli), kColumns}}, resuming), schedule_(scene.moduli) {}
  std::string name() const override { return "moduli"; }
  Needs needs() const override { return Needs{.contacts = true, .network = true}; }

  void on_step_accepted(const StepAccepted& e) override {
    if (tools::due_every(schedule_, e.state)) write("every", e.state, std::nullopt);
  }
  void on_jammed(const Jammed& e) override {
    if (schedule_.at_jamming) write("jamming", e.state, std::nullopt);
  }
  void on_target_reached(const TargetReached& e) override {
    if (schedule_.at_targets) write("target", e.state, e.target.dphi);
  }
  void on_depleted(const Depleted& e) override {
    if (schedule_.at_phi2) write("phi2", e.state, std::nullopt);
  }

 private:
  const ElasticResponse* compute(const StateView& s, std::string& error) {
    if (cached_step_ == s.step && (cached_ || !cached_error_.empty())) {
      error = cached_error_;
      return cached_ ? &*cached_ : nullptr;
    }
    cached_step_ = s.step;
    cached_.reset();
    cached_error_.clear();
    if (!s.contacts || !s.network) {
      cached_error_ = "no contacts";
    } else {
      try {
        cached_ = elastic_response(*s.packing, *s.contacts, *s.network);
      } catch (const std::exception& ex) {
        cached_error_ = std::string("error: ") + ex.what();  // e.g. an unstable state: logged, run goes on
      }
    }
    error = cached_error_;
    return cached_ ? &*cached_ : nullptr;
  }

  void write(const char* event, const StateView& s, std::optional<double> dphi) {
    std::string error;
    const ElasticResponse* r = compute(s, error);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double n_J = s.jamming ? s.jamming->n_J : nan;
    if (!r) {
      std::vector<io::CsvField> row{event, s.step, s.phi, dphi};
      while (row.size() < kColumns.size() - 8) row.push_back(io::CsvField::missing());
      row.insert(row.end(), {error, io::CsvField::missing(), io::CsvField::missing(), io::CsvField::missing(),
                             io::CsvField::missing(), io::CsvField::missing(), false, io::CsvField::missing()});
      log().row(row);
      return;
    }
    const ElasticResponse& e = *r;
    const double l2 = e.ell_c * e.ell_c;
    const KernelTreatment& k = e.kernel;
    log().row({event,
               s.step,
               s.phi,
               dphi,
               e.N,
               e.N_nr,
               e.N_f,
               e.N_u,
               e.N_u_buds,
               e.contacts,
               e.Z,
               e.Z_iso,
               e.dZ,
               e.P,
               e.P_energy,
               e.moduli.B,
               e.moduli.G_simple,
               e.moduli.G_pure,
               e.moduli.G_mean,
               e.moduli_affine.B,
               e.moduli_affine.G_simple,
               e.moduli_affine.G_pure,
               e.moduli_energy.B,
               e.moduli_energy.G_simple,
               e.moduli_energy.G_pure,
               e.G_energy(),
               e.shear.G_min,
               e.shear.stable,
               e.shear_stress.G_min,
               e.C(0, 0),
               e.C(1, 1),
               e.C(0, 1),
               e.C(2, 2),
               e.C(0, 2),
               e.C(1, 2),
               e.n,
               n_J,
               e.ell_c,
               e.M4,
               e.B_ext,
               e.G_mf,
               n_J * kSpring * l2 * e.Z / 8.0,
               n_J * kSpring * l2 * e.M4 * e.dZ / 2.0,
               to_string(k.method),
               k.pinned_translation,
               k.pinned_lobe_rotation,
               k.pinned_zero_rows,
               k.residual,
               k.kernel_component,
               k.well_posed,
               k.unstable_modes});
  }

  Schedule schedule_;
  long cached_step_ = -1;
  std::optional<ElasticResponse> cached_;
  std::string cached_error_;
};

const tools::ObserverRegistration registration{"moduli",
                                               "observe.moduli.*",
                                               {std::string(io::run_files::moduli)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.moduli.any())
                                                   return nullptr;  // not asked: never built, costs nothing
                                                 return std::make_unique<ModuliLog>(c.scene, c.run_dir.root(),
                                                                                    c.resuming);
                                               }};

}  // namespace
}  // namespace budjam::tools::moduli_observer
