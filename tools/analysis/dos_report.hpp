#pragma once
// The vibrational spectrum of one packing as files (docs/spectrum.md, "Outputs"), shared by
// `budjam dos` and the growth-run observer "dos":
//   <base>.dos.json   summary: method, N_zero at four cutoffs, ω*, N_u and N_u_buds from the contact
//                     network, floppy modes from the pebble game, D(ω) histogram
//   <base>.dos.csv    one row per computed mode: mode, lambda (ω²), omega (signed), participation,
//                     quasi_zero
// Both files are deterministic (no timings; same packing and options => same bytes).
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/rigidity.hpp"
#include "budjam/spectrum.hpp"
#include "io/json.hpp"
#include "io/result_files.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace budjam::tools {

struct DosRequest {
  SpectrumOptions spectrum{.modes = 0};  // modes 0: as many as ω* needs
  BandEdgeRule rule;
  std::size_t bins = 50;    // D(ω) histogram bins on [0, ω_max of the computed modes]
  bool pebble_game = true;  // also count floppy modes with the pebble game
};

struct DosReport {
  PackingSpectrum result;
  ContactNetwork network;
  bool has_rigidity = false;
  RigidityState rigidity;
  DosHistogram histogram;
  double L = 0, phi = 0;  // of the packing: they tie a sidecar to it (tools::sidecar)
  double seconds = 0;     // wall time of the spectrum (not written to the files)
};

// Spectrum, observables and the independent counts of one relaxed packing. Throws NoResultError if
// the packing has no non-rattler cell.
DosReport dos_report(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                     const DosRequest& request);

io::Json dos_json(const DosReport& report, const DosRequest& request);

// The JSON, the eigenvalue table (mode, lambda, omega, participation, quasi_zero) and dos_line;
// the CSV writer refers to `report`, which must outlive it.
io::CommandResult dos_result(const DosReport& report, const DosRequest& request);

// Writes <stem>.dos.json and <stem>.dos.csv atomically in `dir` (the sidecar files of a run's
// packings); returns the two paths, JSON first.
std::vector<std::filesystem::path> write_dos_files(const io::Directory& dir, const std::string& stem,
                                                   const DosReport& report, const DosRequest& request);

// One-line summary for a terminal.
std::string dos_line(const DosReport& report);

}  // namespace budjam::tools
