// Observer "trajectory": the run as a particle trajectory for OVITO and ASE, <run_dir>/trajectory.xyz
// (extended XYZ, one frame per sampled state, io/export.hpp), only when the scene asks
// ([observe] trajectory_every = k > 0). A frame is written every k accepted steps and at every
// event state: jamming, each Δφ target, φ_2, and the last state. Each frame carries its growth
// step; the number of particles changes with divisions (extended XYZ allows it).
//
// Like the CSV logs, frames go to trajectory.xyz.partial, each frame one whole write, and the file
// is renamed to trajectory.xyz when the run ends; a checkpoint records its length so that --resume
// cuts off the frames written after it.
#include "observers/observers.hpp"

#include "io/atomic_file.hpp"
#include "io/export.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <istream>
#include <ostream>
#include <string>

namespace {

using namespace budjam;
namespace fs = std::filesystem;

class TrajectoryLog : public Observer {
 public:
  TrajectoryLog(long every, fs::path dir, bool resuming)
      : every_(every), path_(std::move(dir) / "trajectory.xyz"), partial_(fs::path(path_) += ".partial") {
    if (!resuming) open(O_TRUNC);
  }
  ~TrajectoryLog() override {
    if (fd_ >= 0) ::close(fd_);
  }
  std::string name() const override { return "trajectory"; }

  void on_step_accepted(const StepAccepted& e) override {
    if (e.state.step % every_ == 0) frame(e.state);
  }
  void on_jammed(const Jammed& e) override { frame(e.state); }
  void on_target_reached(const TargetReached& e) override { frame(e.state); }
  void on_depleted(const Depleted& e) override { frame(e.state); }
  void on_finished(const Finished& e) override { finish(e.state); }
  void on_failed(const Failed& e) override { finish(e.state); }

  void save_state(std::ostream& os) override {
    sync();
    os << bytes_ << ' ' << last_step_ << '\n';
  }
  void load_state(std::istream& is) override {
    if (!(is >> bytes_ >> last_step_)) throw InputError("checkpoint: trajectory: expected <bytes> <last step>");
    std::error_code ec;
    if (!fs::exists(partial_) || fs::file_size(partial_, ec) < bytes_)
      throw InputError(partial_.string() + ": missing or shorter than the checkpoint records");
    fs::resize_file(partial_, bytes_);
    open(0);
  }

 private:
  void open(int flags) {
    fd_ = ::open(partial_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | flags, 0644);
    if (fd_ < 0) throw io::IoError(partial_.string() + ": cannot open: " + std::strerror(errno));
  }
  // One frame per state: an event state that is also a sampled step is written once.
  void frame(const StateView& s) {
    if (s.step == last_step_) return;
    io::ParticleFrame f = io::particle_frame(*s.packing);
    f.step = s.step;
    const std::string text = io::format_extxyz(f);
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw io::IoError(partial_.string() + ": write failed: " + std::strerror(errno));
      done += static_cast<std::size_t>(n);
    }
    bytes_ += text.size();
    last_step_ = s.step;
  }
  void sync() {
    if (::fsync(fd_) != 0) throw io::IoError(partial_.string() + ": fsync failed: " + std::strerror(errno));
  }
  void finish(const StateView& s) {
    frame(s);
    sync();
    fs::rename(partial_, path_);
  }

  long every_;
  fs::path path_, partial_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  long last_step_ = -1;
};

const tools::ObserverRegistration reg{"trajectory", [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                        if (c.scene.trajectory_every <= 0) return nullptr;
                                        return std::make_unique<TrajectoryLog>(c.scene.trajectory_every, c.run_dir,
                                                                               c.resuming);
                                      }};

}  // namespace
