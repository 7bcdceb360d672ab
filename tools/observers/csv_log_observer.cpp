#include "observers/csv_log_observer.hpp"

#include "budjam/scene.hpp"
#include "io/text.hpp"

#include <cmath>
#include <cstdio>
#include <istream>
#include <ostream>
#include <stdexcept>

namespace budjam::tools {

CsvLogObserver::CsvLogObserver(const io::Directory& dir, std::vector<LogSpec> logs, bool resuming)
    : dir_(dir), specs_(std::move(logs)), logs_(specs_.size()) {
  if (resuming) return;
  for (std::size_t k = 0; k < specs_.size(); ++k) logs_[k].emplace(dir_, specs_[k].name, specs_[k].columns);
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
  cuts_.clear();
  for (std::size_t k = 0; k < specs_.size(); ++k)
    cuts_.push_back(io::CsvLog::check_resumable(dir_, specs_[k].name, specs_[k].columns, bytes[k]));
  load_more(is);
}

void CsvLogObserver::on_resumed() {
  if (cuts_.size() != specs_.size()) throw std::logic_error(name() + ": resumed without its checkpoint section");
  for (std::size_t k = 0; k < specs_.size(); ++k)
    logs_[k].emplace(io::CsvLog::resume(dir_, specs_[k].name, specs_[k].columns, cuts_[k].bytes));
}

const io::CsvLog::Cut& CsvLogObserver::resumed_cut(std::size_t k) const {
  if (k >= cuts_.size()) throw std::logic_error(name() + ": no checkpointed log lengths");
  return cuts_[k];
}

std::string CsvLogObserver::resumed_file(std::size_t k) const {
  return (dir_ / io::interrupted_log_file(dir_, specs_.at(k).name)).string();
}

std::string CsvLogObserver::resumed_text(std::size_t k) const {
  return io::read_text_file(dir_, io::interrupted_log_file(dir_, specs_.at(k).name)).substr(0, resumed_cut(k).bytes);
}

std::vector<std::string> CsvLogObserver::resumed_rows(std::size_t k) const {
  const std::string text = resumed_text(k);
  std::vector<std::string> rows;
  std::size_t at = text.find('\n') + 1;  // after the header
  for (std::size_t end; (end = text.find('\n', at)) != std::string::npos; at = end + 1)
    rows.push_back(text.substr(at, end - at));
  return rows;
}

void CsvLogObserver::refuse_resumed(std::size_t k, const std::string& what) const {
  throw InputError(io::escape_control(resumed_file(k) + ": " + what));
}

bool due_every(const Schedule& schedule, const StateView& s) {
  if (schedule.every <= 0 || s.phase != Phase::jammed || s.jamming == nullptr) return false;
  const long since = s.step - s.jamming->step;
  return since > 0 && since % schedule.every == 0;
}

io::CsvField beyond_double_range(double value, double log_value) {
  if (std::isnormal(value) || (value == 0.0 && log_value == -HUGE_VAL)) return io::CsvField(value);
  const double log10_value = log_value / std::log(10.0);
  double exponent = std::floor(log10_value);
  double mantissa = std::pow(10.0, log10_value - exponent);
  if (mantissa >= 9.9999999999995) mantissa /= 10.0, exponent += 1.0;  // would print as 10
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.13ge%+.0f", mantissa, exponent);
  return io::CsvField(std::string_view(buf));
}

}  // namespace budjam::tools
