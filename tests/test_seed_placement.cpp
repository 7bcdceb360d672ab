// Random seed placement (init.kind = "random_seeds"): memory bounded by the number of seeds, not
// by the box area (that the seeds do not overlap is test_growth's).
#include "budjam/growth.hpp"
#include "budjam/scene.hpp"

#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace budjam;

namespace {

Scene seeds_scene(double L, std::size_t n) {
  Scene s;
  s.L = L;
  s.init = InitialState::random_seeds;
  s.n_seeds = n;
  return s;
}

}  // namespace

TEST_CASE("placing a few seeds in a huge box needs little memory", "[seed_placement]") {
  // L = 1e4 used to allocate (L/1.01)² ≈ 10⁸ bins (2.3 GB); the child runs under a 256 MiB
  // address-space limit and must place its seeds all the same.
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const rlimit lim{256u << 20, 256u << 20};
    ::setrlimit(RLIMIT_AS, &lim);
    try {
      Rng rng(1);
      const Packing p = random_seeds(seeds_scene(1e4, 20), rng);
      ::_exit(p.size() == 20 ? 0 : 1);
    } catch (...) {
      ::_exit(2);
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}
