// Observer "progress": one line on stderr every 2 s and at each event (not with --quiet or
// [observe] progress = false): step, φ, what the run grows toward, N, P, phase, growth steps/s
// and the run directory. Stateless: a resumed run may show it or not.
#include "observers/observers.hpp"

#include "io/text.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace budjam::tools::progress_observer {
namespace {

class Progress : public Observer {
 public:
  explicit Progress(std::filesystem::path dir) : dir_(std::move(dir)) {}
  std::string name() const override { return "progress"; }
  void on_step_accepted(const StepAccepted& e) override {
    const auto now = Clock::now();
    if (!started_) {  // the initial (or resumed) state: the rate counts from here
      started_ = true;
      start_ = now;
      start_attempts_ = e.state.attempts;
    }
    if (now - last_ < std::chrono::seconds(2)) return;
    line("", e.state, now);
  }
  void on_jammed(const Jammed& e) override { line("jammed: ", e.state, Clock::now()); }
  void on_unjammed(const Unjammed& e) override {
    line("unjammed (the packing lost its rigidity; jamming is searched again and the Δφ targets restart): ", e.state,
         Clock::now());
  }
  void on_target_reached(const TargetReached& e) override {
    line("target dphi=" + io::format_double(e.target.dphi) + ": ", e.state, Clock::now());
  }
  void on_depleted(const Depleted& e) override { line("phi_2: ", e.state, Clock::now()); }
  void on_finished(const Finished& e) override { line("finished: ", e.state, Clock::now()); }
  void on_failed(const Failed& e) override {
    // The step limit is an expected stop (exit 0, docs/files.md); the rest are failures (exit 1).
    const bool expected = e.result.status == RunStatus::step_limit;
    line(std::string(expected ? "stopped (" : "FAILED (") + to_string(e.result.status) + "): ", e.state, Clock::now());
  }

 private:
  using Clock = std::chrono::steady_clock;

  // What the run grows toward now: φ_J, the next φ_J + Δφ target, or φ_2. A target landed on (within
  // jamming.target_tolerance, on either side) is behind the run.
  static std::string heading(const StateView& s) {
    if (!s.jamming || !s.scene) return "toward phi_J";
    for (const double dphi : s.scene->targets)
      if (s.jamming->phi + dphi > s.phi + s.scene->target_tolerance) return "toward phi_J+" + io::format_double(dphi);
    return s.scene->continue_to_phi2 ? "toward phi_2" : "at the last target";
  }

  void line(const std::string& what, const StateView& s, Clock::time_point now) {
    // Growth steps tried per second since this session started (a rate over the last few
    // milliseconds would read 0 at an event that follows a progress line).
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed > 0 ? static_cast<double>(s.attempts - start_attempts_) / elapsed : 0.0;
    char buf[160];
    std::snprintf(buf, sizeof buf, "step %ld  phi %.8f  %s  N %zu  P %.3e  %s  %.1f steps/s  -> ", s.step, s.phi,
                  heading(s).c_str(), s.packing->size(), s.P, to_string(s.phase), rate);
    std::cerr << "grow: " << what << buf << io::escape_control(dir_.string()) << '\n';
    last_ = now;
  }

  std::filesystem::path dir_;
  Clock::time_point last_ = Clock::now();
  bool started_ = false;
  Clock::time_point start_;
  long start_attempts_ = 0;
};

const tools::ObserverRegistration registration{
    "progress", "observe.progress", {}, [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
      if (c.quiet || !c.scene.progress) return nullptr;
      return std::make_unique<Progress>(c.run_dir.path());
    }};

}  // namespace
}  // namespace budjam::tools::progress_observer
