#include "visproxy/core/version.h"

namespace visproxy {

const char* version() { return VISPROXY_VERSION; }

}  // namespace visproxy
