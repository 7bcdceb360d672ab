#pragma once
// A small tmpfs for disk-full tests: mounted when the tests run as root, otherwise (or when the
// mount fails) `mounted` is false and the caller skips with a message.
#include <sys/mount.h>
#include <unistd.h>
#include <filesystem>
#include <string>

namespace budjam::testing {

struct SmallDisk {
  std::filesystem::path path;
  bool mounted = false;
  std::string why_not;

  SmallDisk(const std::filesystem::path& where, std::size_t bytes) : path(where) {
    std::filesystem::create_directories(path);
    if (::geteuid() != 0) {
      why_not = "not root: disk-full test skipped";
      return;
    }
    const std::string opts = "size=" + std::to_string(bytes);
    mounted = ::mount("tmpfs", path.c_str(), "tmpfs", 0, opts.c_str()) == 0;
    if (!mounted) why_not = "tmpfs mount failed: disk-full test skipped";
  }
  ~SmallDisk() {
    if (mounted) ::umount2(path.c_str(), MNT_DETACH);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;
};

}  // namespace budjam::testing
