#pragma once
// How the process's heap treats the large blocks that sparse factorisations allocate and free.
namespace budjam::io {

// Keeps freed memory mapped and reuses it instead of handing it back to the kernel. Every Newton or
// active-set step of a large packing allocates and frees its factor and matrices (tens to hundreds of
// MiB at 10⁵ cells); glibc serves blocks that large with mmap and unmaps them when they are freed, so
// each new factor is faulted in page by page — at 10⁵ cells the kernel's page faults were about a
// quarter of the active-set steps' CPU (docs/speed.md, "Large packings"). After this call every block
// comes from the heap, which is never trimmed: a freed block's pages serve the next one, at the price
// of the process keeping its peak footprint. Results do not depend on it. For executables (budjam,
// the benchmarks), once, at the start of main: it sets process-wide allocator state, which a library
// must not. Returns false where the C library has no such settings (then nothing changes).
bool keep_freed_memory();

}  // namespace budjam::io
