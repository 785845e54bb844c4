// millcharge devices: the OpenCL devices and the platforms that offer none.
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "app/commands.h"
#include "compute/context.h"

namespace mc::app {

int cmd_devices() {
  const auto devices = compute::list_devices();
  if (devices.empty()) {
    std::cerr << "millcharge: OpenCL: " << compute::no_device_message() << '\n';
    return 1;
  }
  for (const auto& d : devices)
    std::printf("%s\n    %s, %s, %d compute units, %.1f GiB, fp64 %s, gl sharing %s\n", d.label().c_str(),
                d.version.c_str(), d.c_version.c_str(), d.compute_units, d.global_mem_bytes / 1073741824.0,
                d.fp64 ? "yes" : "no", d.gl_sharing ? "yes" : "no");
  for (const auto& [index, name] : compute::platforms_without_devices()) {
    std::printf("platform %d (%s): no devices", index, name.c_str());
    if (name == "rusticl" && !std::getenv("RUSTICL_ENABLE"))
      std::printf(" (Mesa's rusticl offers one when RUSTICL_ENABLE names a driver: RUSTICL_ENABLE=llvmpipe for the CPU)");
    std::printf("\n");
  }
  return 0;
}

}  // namespace mc::app
