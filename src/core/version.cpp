#include "core/version.h"

#include "mc_version.h"  // generated: MC_BUILD_COMMIT

namespace mc {

const char* version() { return MC_VERSION; }
const char* build_commit() { return MC_BUILD_COMMIT; }
std::string version_line() { return std::string("millcharge ") + version() + " (commit " + build_commit() + ")"; }

}  // namespace mc
