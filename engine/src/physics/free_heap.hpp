// Giving freed memory back to the system. glibc keeps the pages of a block freed inside its heap
// (any block under its mmap threshold, which rises to 32 MB once a large block has been freed):
// they stay resident, and a later block that does not fit in the gap takes new pages beside them.
// At a million discs the setup's temporaries (the scene's parse, the fill's file, the first list
// build's scratch) leave 23 MB of such gaps resident through the run. malloc_trim hands their
// pages back; they are taken again, zeroed, only when needed. Once, after the setup: after every
// list build (its cell sort, 7 MB at a million discs) it costs the settled 1M loop 9 %.
#pragma once

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace dem {

// Not under AddressSanitizer. Its allocator replaces malloc, so glibc's own never starts, and
// malloc_trim starts it: each thread that calls it first sets its arena to the main arena without
// counting itself there. Two `dem ensemble` workers trimming at once then broke glibc: a null read
// in mtrim, or "a->attached_threads > 0" failing as the second of them exited. There is nothing
// of glibc's to trim in that build anyway.
#if defined(__SANITIZE_ADDRESS__)
#define DEM_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)  // clang before 14 says it only this way
#define DEM_UNDER_ASAN 1
#endif
#endif

inline void release_free_heap() {
#if defined(__GLIBC__) && !defined(DEM_UNDER_ASAN)
  malloc_trim(0);
#endif
}

}  // namespace dem
