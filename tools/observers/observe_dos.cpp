// Growth-run observer "dos" (scene [observe.dos]): the vibrational spectrum at jamming, at φ_2,
// at each target and/or every k accepted steps above jamming (docs/spectrum.md, "Outputs": "In a
// growth run").
//   packings/jammed.dos.{json,csv}, packings/phi2.dos.*, packings/target_<k>.dos.*  beside the
//       packings RunLog writes (so `budjam analyse` finds them as sidecars)
//   spectra/step_<n>.dos.{json,csv}  for `every`
//   dos.csv  one row per spectrum (resumable log)
// Defaults of `budjam dos`: automatic method, as many modes as ω* needs.
#include "analysis/dos_report.hpp"
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "io/atomic_file.hpp"
#include "io/run_directory.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace budjam::tools::dos_observer {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kColumns{"episode",  "step",         "kind",       "dphi",     "phi",    "N",
                                        "N_nr",     "method",       "n_dof",      "computed", "N_zero", "N_u",
                                        "N_u_buds", "floppy_modes", "omega_star", "Z",        "dZ"};

class DosObserver : public tools::CsvLogObserver {
 public:
  DosObserver(const Scene& scene, const io::RunDirectory& dir, bool resuming)
      : CsvLogObserver(dir.root(), {{std::string(io::run_files::dos), kColumns}}, resuming),
        schedule_(scene.dos),
        dir_(dir) {}
  std::string name() const override { return "dos"; }
  Needs needs() const override {
    Needs n;
    n.contacts = n.network = schedule_.every > 0;
    return n;
  }

  void on_jammed(const Jammed& e) override {
    if (schedule_.at_jamming)
      record(e.state, "jammed", io::run_files::packings, std::string(io::run_files::jammed), std::nullopt);
  }
  void on_depleted(const Depleted& e) override {
    if (schedule_.at_phi2)
      record(e.state, "phi2", io::run_files::packings, std::string(io::run_files::phi2), std::nullopt);
  }
  void on_target_reached(const TargetReached& e) override {
    if (schedule_.at_targets)
      record(e.state, "target", io::run_files::packings, io::run_files::target_stem(e.target.index), e.target.dphi);
  }
  void on_step_accepted(const StepAccepted& e) override {
    const StateView& s = e.state;
    if (!tools::due_every(schedule_, s)) return;
    record(s, "step", io::run_files::spectra, "step_" + std::to_string(s.step), std::nullopt);
  }

 private:
  // <sub>/<stem>.dos.{json,csv}: beside a run packing, or a spectrum of its own
  void record(const StateView& s, const std::string& kind, std::string_view sub, const std::string& stem,
              std::optional<double> dphi) {
    if (s.contacts == nullptr || s.network == nullptr)
      throw std::logic_error("dos observer: the driver gave no contact network at a " + kind + " state");
    if (s.network->N_nr == 0) return;  // no non-rattler: nothing vibrates
    const tools::DosReport r = tools::dos_report(*s.packing, *s.contacts, *s.network, request_);
    tools::write_dos_files(dir_.subdirectory(sub), stem, r, request_);
    const auto& m = r.result.summary;
    log().row({static_cast<long>(s.jamming ? s.jamming->episode : -1), s.step, kind,
               dphi ? io::CsvField(*dphi) : io::CsvField::missing(), s.phi, s.packing->size(), r.network.N_nr,
               to_string(m.method), m.n_dof, m.computed, m.N_zero, r.network.N_u, r.network.N_u_buds,
               r.has_rigidity ? io::CsvField(r.rigidity.floppy_plane) : io::CsvField::missing(),
               m.band.available ? io::CsvField(m.band.omega_star) : io::CsvField::missing(), r.network.Z,
               r.network.dZ});
  }

  Schedule schedule_;
  const io::RunDirectory& dir_;
  tools::DosRequest request_;
};

const tools::ObserverRegistration registration{
    "dos", "observe.dos.*",
    [] {
      io::OwnedEntries files{std::string(io::run_files::dos)};
      for (auto& e :
           io::run_files::entries_with_suffixes(io::run_files::spectra, "step_#", io::run_files::spectrum_suffixes()))
        files.push_back(std::move(e));
      return files;
    }(),
    [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
      if (!c.scene.dos.any()) return nullptr;
      return std::make_unique<DosObserver>(c.scene, c.run_dir, c.resuming);
    }};

}  // namespace
}  // namespace budjam::tools::dos_observer
