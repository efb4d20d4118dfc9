#pragma once
// The library's version, as the installed package and every manifest state it.

namespace visproxy {

/// "MAJOR.MINOR.PATCH" of the library this program runs with (which may be newer than the
/// headers it was compiled against, within the same minor version).
const char* version();

}  // namespace visproxy
