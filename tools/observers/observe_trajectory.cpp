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
#include "io/run_directory.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <istream>
#include <ostream>
#include <string>

namespace budjam::tools::trajectory_observer {
namespace {

class TrajectoryLog : public Observer {
 public:
  TrajectoryLog(long every, const io::Directory& dir, bool resuming) : every_(every), dir_(dir) {
    if (resuming) return;
    dir_.remove(io::run_files::trajectory);
    dir_.remove(partial_name());
    fd_ = dir_.open_file(partial_name(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND);
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
    // A frame ends with a newline: the recorded length must be the end of one.
    const std::string file = io::interrupted_log_file(dir_, std::string(io::run_files::trajectory));
    const int fd = dir_.open_file(file, O_RDONLY);
    struct ::stat st {};
    char last = 0;
    const bool ok = ::fstat(fd, &st) == 0 && static_cast<std::uint64_t>(st.st_size) >= bytes_ &&
                    (bytes_ == 0 || (::pread(fd, &last, 1, static_cast<off_t>(bytes_ - 1)) == 1 && last == '\n'));
    ::close(fd);
    if (!ok)
      throw InputError((dir_ / file).string() + ": does not hold whole frames up to the " + std::to_string(bytes_) +
                       " bytes the checkpoint records");
  }
  void on_resumed() override {
    io::reopen_interrupted_log(dir_, std::string(io::run_files::trajectory));
    fd_ = dir_.open_file(partial_name(), O_WRONLY | O_APPEND);
    if (::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0)
      throw io::IoError((dir_ / partial_name()).string() + ": cannot truncate: " + std::strerror(errno));
  }

 private:
  static std::string partial_name() { return std::string(io::run_files::trajectory) + ".partial"; }
  // One frame per state: an event state that is also a sampled step is written once.
  void frame(const StateView& s) {
    if (s.step == last_step_) return;
    io::ParticleFrame f = io::particle_frame(*s.packing);
    f.step = s.step;
    const std::string text = io::format_extxyz(f);
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw io::IoError((dir_ / partial_name()).string() + ": write failed: " + std::strerror(errno));
      done += static_cast<std::size_t>(n);
    }
    bytes_ += text.size();
    last_step_ = s.step;
  }
  void sync() {
    if (::fsync(fd_) != 0)
      throw io::IoError((dir_ / partial_name()).string() + ": fsync failed: " + std::strerror(errno));
  }
  void finish(const StateView& s) {
    frame(s);
    sync();
    dir_.rename(partial_name(), io::run_files::trajectory);
  }

  long every_;
  io::Directory dir_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  long last_step_ = -1;
};

const tools::ObserverRegistration reg{
    "trajectory",
    "observe.trajectory_every",
    // trajectory.gsd: a conversion of an earlier run's trajectory.xyz
    {std::string(io::run_files::trajectory), std::string(io::run_files::trajectory_gsd)},
    [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
      if (c.scene.trajectory_every <= 0) return nullptr;
      return std::make_unique<TrajectoryLog>(c.scene.trajectory_every, c.run_dir.root(), c.resuming);
    }};

}  // namespace
}  // namespace budjam::tools::trajectory_observer
