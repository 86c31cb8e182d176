#pragma once
// The host's memory allocator tuned for the simulator's pattern of allocation (host speed
// only: no result depends on it). pp5sim calls it before anything else runs (from its
// .preinit_array, sim/app/main.cpp), and the benchmarks call it first, so that they measure
// frames as pp5sim runs them.

namespace pp5 {

// Host speed only (no result depends on it). Measured on the Banks frame (perf): page faults
// had become the largest cost after the simulation's own work, each first touch of a 4 KB
// page costing microseconds in a virtual machine.
//  - A frame allocates and frees pixel arrays of hundreds of KB per Renderer board, which glibc
//    would hand to mmap and back to the kernel when freed, so every board paid for its pages
//    afresh: freed memory stays in the process instead (mmap and trim thresholds).
//  - The heap is grown by 64 MB at once and advised to use transparent huge pages (where the
//    kernel offers them on request, "madvise" mode): one fault per 2 MB instead of 512.
//    Untouched pages cost nothing; on a kernel without them the advice is ignored. The Banks
//    frame's page faults went from about 4,600 to about 2,000 and its wall time down by 11
//    to 18% (perf stat -r 5, alternating with the build before).
//  - The heap's head below its first huge page (up to 2 MB, wherever address-space
//    randomisation put the heap) is taken by an allocation never touched, so that what comes
//    next starts in the huge pages: SystemC's static initialisers zero 3 MB, which had
//    faulted 0 to 512 small pages from run to run. pp5sim --version: 220 to 660 page faults
//    before, 228 every run after; the Banks frame 570 to 1,030 before, 571 after.
// Only C library calls: safe before any C++ static initialiser has run.
void tune_host_memory();

}  // namespace pp5
