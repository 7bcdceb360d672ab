#include "observers/csv_log_observer.hpp"

#include "budjam/scene.hpp"

#include <istream>
#include <ostream>
#include <stdexcept>

namespace budjam::tools {

CsvLogObserver::CsvLogObserver(std::vector<LogSpec> logs, bool resuming)
    : specs_(std::move(logs)), logs_(specs_.size()) {
  if (resuming) return;
  for (std::size_t k = 0; k < specs_.size(); ++k) logs_[k].emplace(specs_[k].path, specs_[k].columns);
}

io::CsvLog& CsvLogObserver::log(std::size_t k) {
  if (!logs_.at(k)) throw std::logic_error(name() + ": log not open (resumed without its checkpoint section)");
  return *logs_[k];
}

void CsvLogObserver::finish() {
  for (std::size_t k = 0; k < logs_.size(); ++k) log(k).finish();
}

void CsvLogObserver::save_state(std::ostream& os) {
  for (std::size_t k = 0; k < logs_.size(); ++k) {
    log(k).sync();
    os << (k ? " " : "") << log(k).bytes();
  }
  os << '\n';
  save_more(os);
}

void CsvLogObserver::load_state(std::istream& is) {
  std::vector<std::uint64_t> bytes(specs_.size());
  for (auto& b : bytes)
    if (!(is >> b)) throw InputError("bad " + name() + " state (log lengths)");
  for (std::size_t k = 0; k < specs_.size(); ++k)
    logs_[k].emplace(io::CsvLog::resume(specs_[k].path, specs_[k].columns, bytes[k]));
  load_more(is);
}

bool due_every(const Schedule& schedule, const StateView& s) {
  if (schedule.every <= 0 || s.phase != Phase::jammed || s.jamming == nullptr) return false;
  const long since = s.step - s.jamming->step;
  return since > 0 && since % schedule.every == 0;
}

}  // namespace budjam::tools
