#pragma once
// Settings a program built on visproxy may make for its whole process. The library never
// makes them itself: they belong to the program.

namespace visproxy {

/// Turns transparent huge pages off for this process and the processes it starts
/// (Linux's PR_SET_THP_DISABLE), unless the environment variable
/// VISPROXY_TRANSPARENT_HUGE_PAGES is set to 1. Returns whether they are now off.
///
/// Embree marks every large block of its BVH builders as a huge-page candidate
/// (madvise MADV_HUGEPAGE). Where the kernel must first assemble free 2 MiB pages, or a
/// virtual machine must first fetch them from its host, touching them costs far more than
/// touching small pages: on the 2-core virtual machine this project is measured on, a fresh
/// process took 8.5 s to touch its first GiB of huge pages against 0.45 s for small ones,
/// and building the BVH of a 4.8 M-triangle mesh took 4.4 s with huge pages against 0.8 s
/// without (0.65 s with them once the process had touched them). The visproxy command and
/// its benchmarks call this first.
bool disable_transparent_huge_pages();

}  // namespace visproxy
