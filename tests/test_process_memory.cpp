// The process's memory policy (io/process_memory.hpp): with keep_freed_memory, a large block that
// was freed serves the next allocation without the kernel faulting its pages in again; without it
// (glibc's default) each such block is mapped afresh. Its own executable: the policy is process-wide.
#include "io/process_memory.hpp"

#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <unistd.h>
#include <cstdlib>
#include <cstring>

namespace {

long minor_faults() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return r.ru_minflt;
}

// Page faults taken while a block of `bytes` is allocated, written through and freed.
long faults_to_fill(std::size_t bytes) {
  const long before = minor_faults();
  char* block = static_cast<char*>(std::malloc(bytes));
  REQUIRE(block != nullptr);
  std::memset(block, 1, bytes);
  asm volatile("" : : "r"(block) : "memory");  // the writes are not optimised away
  std::free(block);
  return minor_faults() - before;
}

}  // namespace

TEST_CASE("keep_freed_memory: a freed 64 MiB block serves the next one without new page faults") {
  constexpr std::size_t bytes = std::size_t{64} << 20;  // above glibc's largest mmap threshold (32 MiB)
  const long pages = static_cast<long>(bytes) / sysconf(_SC_PAGESIZE);
  // glibc's default: every such block is mapped afresh and faulted in again, page by page.
  faults_to_fill(bytes);
  CHECK(faults_to_fill(bytes) > pages / 2);
  REQUIRE(budjam::io::keep_freed_memory());
  faults_to_fill(bytes);  // the heap grows to hold it once
  CHECK(faults_to_fill(bytes) < pages / 100);
  CHECK(faults_to_fill(bytes / 2) < pages / 100);  // a smaller block fits in the same pages
}
