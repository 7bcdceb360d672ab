// Observer "progress": one line on stderr every 2 s and at each event (not with --quiet or
// [observe] progress = false). Stateless: a resumed run may show it or not.
#include "observers/observers.hpp"

#include "io/text.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>

namespace {

using namespace budjam;

class Progress : public Observer {
 public:
  std::string name() const override { return "progress"; }
  void on_step_accepted(const StepAccepted& e) override {
    const auto now = Clock::now();
    if (now - last_ < std::chrono::seconds(2)) return;
    line("", e.state, now);
  }
  void on_jammed(const Jammed& e) override { line("jammed: ", e.state, Clock::now()); }
  void on_unjammed(const Unjammed& e) override { line("unjammed (jamming search restarts): ", e.state, Clock::now()); }
  void on_target_reached(const TargetReached& e) override {
    line("target dphi=" + io::format_double(e.target.dphi) + ": ", e.state, Clock::now());
  }
  void on_depleted(const Depleted& e) override { line("phi_2: ", e.state, Clock::now()); }
  void on_finished(const Finished& e) override { line("finished: ", e.state, Clock::now()); }
  void on_failed(const Failed& e) override {
    line(std::string("FAILED (") + to_string(e.result.status) + "): ", e.state, Clock::now());
  }

 private:
  using Clock = std::chrono::steady_clock;
  void line(const std::string& what, const StateView& s, Clock::time_point now) {
    const double dt = std::chrono::duration<double>(now - last_).count();
    const double rate = dt > 0 ? static_cast<double>(s.attempts - last_attempts_) / dt : 0.0;
    char buf[256];
    std::snprintf(buf, sizeof buf, "grow: %sstep %ld  phi %.8f  N %zu  P %.3e  %s  %.1f steps/s", what.c_str(), s.step,
                  s.phi, s.packing->size(), s.P, to_string(s.phase), rate);
    std::cerr << buf << '\n';
    last_ = now;
    last_attempts_ = s.attempts;
  }
  Clock::time_point last_ = Clock::now();
  long last_attempts_ = 0;
};

const tools::ObserverRegistration registration{
    "progress", {}, [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
      if (c.quiet || !c.scene.progress) return nullptr;
      return std::make_unique<Progress>();
    }};

}  // namespace
