#pragma once
// The common part of every observer that appends rows to CSV logs in the run directory (steps,
// divisions, bud events, moduli, spectra, rigidity): the logs are created when a run starts, or
// reopened at their checkpointed lengths when it resumes (load_state), synced and measured for
// a checkpoint (save_state), and finished with the run. A subclass adds its own state after the
// lengths with save_more / load_more.
#include "budjam/growth_driver.hpp"
#include "io/atomic_file.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace budjam::tools {

class CsvLogObserver : public Observer {
 public:
  struct LogSpec {
    std::string name;  // in the run directory
    std::vector<std::string> columns;
  };

  bool stateful() const override { return true; }
  void on_finished(const Finished&) override { finish(); }
  void on_failed(const Failed&) override { finish(); }  // a failed run's logs are complete up to the failure
  // One line: the byte length of each log; then save_more's text.
  void save_state(std::ostream& os) final;
  // Checks that each log can be cut at its recorded length (CsvLog::check_resumable); the cut
  // itself waits for on_resumed.
  void load_state(std::istream& is) final;
  void on_resumed() override;

 protected:
  // resuming: the logs are reopened by load_state and on_resumed instead of created.
  CsvLogObserver(const io::Directory& dir, std::vector<LogSpec> logs, bool resuming);
  // The k-th log (in the order given to the constructor); std::logic_error if not open.
  io::CsvLog& log(std::size_t k = 0);
  // What load_state found in the k-th log up to its recorded length; std::logic_error before.
  const io::CsvLog::Cut& resumed_cut(std::size_t k) const;
  // The k-th log's file and its text up to the recorded length (after load_state), header included.
  std::string resumed_file(std::size_t k) const;
  std::string resumed_text(std::size_t k) const;
  // The rows of the k-th log up to its recorded length (after load_state), one string each.
  std::vector<std::string> resumed_rows(std::size_t k) const;
  // InputError "<dir>/<log>.partial: <what>", for check_resumed.
  [[noreturn]] void refuse_resumed(std::size_t k, const std::string& what) const;

  virtual void save_more(std::ostream&) {}
  virtual void load_more(std::istream&) {}

 private:
  void finish();
  io::Directory dir_;
  std::vector<LogSpec> specs_;
  std::vector<std::optional<io::CsvLog>> logs_;
  std::vector<io::CsvLog::Cut> cuts_;
};

// A non-negative quantity known also by its natural log (Δt, χ_c): the double's round-trip text
// while it is a normal double (or 0 with ln = −∞), else decimal text from the log at any size,
// e.g. `4.2e-400` or `1.7e+347` (13 significant digits: the log's own rounding limits them).
io::CsvField beyond_double_range(double value, double log_value);

// Whether `s` is one of the states of an "every k accepted steps above jamming" schedule
// (k = schedule.every > 0): jammed, and k, 2k, ... steps past the jamming point.
bool due_every(const Schedule& schedule, const StateView& s);

}  // namespace budjam::tools
