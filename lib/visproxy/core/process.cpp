#include "visproxy/core/process.h"

#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/prctl.h>
#endif

namespace visproxy {

bool disable_transparent_huge_pages() {
  const char* keep = std::getenv("VISPROXY_TRANSPARENT_HUGE_PAGES");
  if (keep && std::strcmp(keep, "1") == 0) return false;
#if defined(__linux__) && defined(PR_SET_THP_DISABLE)
  return prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0) == 0;
#else
  return false;
#endif
}

}  // namespace visproxy
