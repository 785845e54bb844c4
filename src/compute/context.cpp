#include "compute/context.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <sstream>

namespace mc::compute {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string type_name(cl_device_type t) {
  if (t & CL_DEVICE_TYPE_GPU) return "gpu";
  if (t & CL_DEVICE_TYPE_CPU) return "cpu";
  if (t & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
  return "other";
}

struct Found {
  DeviceInfo info;
  cl::Device device;
};

std::vector<Found> enumerate() {
  std::vector<Found> out;
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    return out;  // no ICD, or an ICD with no platform
  }
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;
    }
    for (std::size_t d = 0; d < devices.size(); ++d) {
      Found f;
      f.device = devices[d];
      DeviceInfo& i = f.info;
      i.platform_index = static_cast<int>(p);
      i.device_index = static_cast<int>(d);
      i.platform_name = platforms[p].getInfo<CL_PLATFORM_NAME>();
      i.name = devices[d].getInfo<CL_DEVICE_NAME>();
      i.type = type_name(devices[d].getInfo<CL_DEVICE_TYPE>());
      i.version = devices[d].getInfo<CL_DEVICE_VERSION>();
      const std::string ext = devices[d].getInfo<CL_DEVICE_EXTENSIONS>();
      i.fp64 = ext.find("cl_khr_fp64") != std::string::npos;
      i.gl_sharing = ext.find("cl_khr_gl_sharing") != std::string::npos;
      i.global_mem_bytes = devices[d].getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
      i.max_alloc_bytes = devices[d].getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
      i.compute_units = static_cast<int>(devices[d].getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
      // Strip the padding some drivers leave in names.
      while (!i.name.empty() && (i.name.back() == ' ' || i.name.back() == '\0')) i.name.pop_back();
      out.push_back(std::move(f));
    }
  }
  return out;
}

Found pick(const std::string& spec_in) {
  const std::vector<Found> all = enumerate();
  if (all.empty())
    throw Error(
        "no OpenCL platform found: install an OpenCL driver (on Debian, "
        "`sudo apt-get install pocl-opencl-icd ocl-icd-libopencl1` for the CPU, "
        "or your GPU vendor's OpenCL driver), or run scripts/setup.sh");
  const std::string spec = lower(spec_in);
  auto first_of_type = [&](const std::string& t) -> const Found* {
    for (const Found& f : all)
      if (f.info.type == t) return &f;
    return nullptr;
  };
  if (spec.empty() || spec == "auto") {
    if (const Found* g = first_of_type("gpu")) return *g;
    return all.front();
  }
  if (spec == "gpu" || spec == "cpu" || spec == "accelerator") {
    if (const Found* f = first_of_type(spec)) return *f;
  } else {
    const auto colon = spec.find(':');
    if (colon != std::string::npos && colon > 0 &&
        std::all_of(spec.begin(), spec.begin() + colon, ::isdigit) &&
        std::all_of(spec.begin() + colon + 1, spec.end(), ::isdigit) &&
        colon + 1 < spec.size()) {
      const int p = std::stoi(spec.substr(0, colon));
      const int d = std::stoi(spec.substr(colon + 1));
      for (const Found& f : all)
        if (f.info.platform_index == p && f.info.device_index == d) return f;
    } else {
      for (const Found& f : all)
        if (lower(f.info.name).find(spec) != std::string::npos ||
            lower(f.info.platform_name).find(spec) != std::string::npos)
          return f;
    }
  }
  std::ostringstream msg;
  msg << "--device '" << spec_in << "' matches no OpenCL device; available:";
  for (const Found& f : all) msg << "\n  " << f.info.label();
  msg << "\nuse auto, gpu, cpu, P:D, or part of a name";
  throw Error(msg.str());
}

}  // namespace

std::string DeviceInfo::label() const {
  std::ostringstream s;
  s << platform_index << ':' << device_index << ' ' << name << " (" << type << ", "
    << platform_name << ')';
  return s.str();
}

std::vector<DeviceInfo> list_devices() {
  std::vector<DeviceInfo> out;
  for (const Found& f : enumerate()) out.push_back(f.info);
  return out;
}

DeviceInfo choose_device(const std::string& spec) { return pick(spec).info; }

Context::Context(const std::string& spec_in) {
  std::string spec = spec_in;
  if (spec.empty())
    if (const char* env = std::getenv("MILLCHARGE_DEVICE")) spec = env;
  Found f = pick(spec);
  info_ = f.info;
  device_ = f.device;
  try {
    context_ = cl::Context(device_);
    queue_ = cl::CommandQueue(context_, device_);
  } catch (const cl::Error& e) {
    throw Error("could not open OpenCL device " + info_.label() + ": " + e.what() +
                " (" + error_name(e.err()) + ")");
  }
}

Context::Context(const std::string& spec_in, const std::vector<cl_context_properties>& gl_properties) {
  std::string spec = spec_in;
  if (spec.empty())
    if (const char* env = std::getenv("MILLCHARGE_DEVICE")) spec = env;
  Found f = pick(spec);
  info_ = f.info;
  device_ = f.device;
  if (!info_.gl_sharing) throw Error(info_.label() + " has no cl_khr_gl_sharing");
  try {
    const cl_platform_id platform = device_.getInfo<CL_DEVICE_PLATFORM>();
    std::vector<cl_context_properties> props = {CL_CONTEXT_PLATFORM,
                                                reinterpret_cast<cl_context_properties>(platform)};
    props.insert(props.end(), gl_properties.begin(), gl_properties.end());
    props.push_back(0);
    // The GL context runs on one device; sharing with another fails later
    // and less clearly, so ask the driver which one it is.
    auto get_gl_info = reinterpret_cast<clGetGLContextInfoKHR_fn>(
        clGetExtensionFunctionAddressForPlatform(platform, "clGetGLContextInfoKHR"));
    if (!get_gl_info) throw Error(info_.platform_name + " does not export clGetGLContextInfoKHR");
    cl_device_id gl_device = nullptr;
    const cl_int err = get_gl_info(props.data(), CL_CURRENT_DEVICE_FOR_GL_CONTEXT_KHR, sizeof gl_device,
                                   &gl_device, nullptr);
    if (err != CL_SUCCESS || gl_device == nullptr)
      throw Error("the driver names no OpenCL device for the GL context (" + error_name(err) + ")");
    if (gl_device != device_())
      throw Error(info_.label() + " is not the device that runs the GL context");
    context_ = cl::Context(device_, props.data());
    queue_ = cl::CommandQueue(context_, device_);
  } catch (const cl::Error& e) {
    throw Error("could not share GL objects with OpenCL device " + info_.label() + ": " + e.what() + " (" +
                error_name(e.err()) + ")");
  }
  shares_gl_ = true;
}

void Context::finish() {
  try {
    queue_.finish();
  } catch (const cl::Error& e) {
    throw Error(std::string("OpenCL queue failed: ") + e.what() + " (" +
                error_name(e.err()) + ")");
  }
}

std::string error_name(int code) {
  switch (code) {
    case CL_SUCCESS: return "CL_SUCCESS";
    case CL_DEVICE_NOT_FOUND: return "CL_DEVICE_NOT_FOUND";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE:
      return "CL_MEM_OBJECT_ALLOCATION_FAILURE: the device is out of memory; use fewer balls or a device with more memory";
    case CL_OUT_OF_RESOURCES: return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY: return "CL_OUT_OF_HOST_MEMORY";
    case CL_BUILD_PROGRAM_FAILURE: return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE: return "CL_INVALID_VALUE";
    case CL_INVALID_BUFFER_SIZE: return "CL_INVALID_BUFFER_SIZE: a buffer is larger than the device allows";
    case CL_INVALID_KERNEL_ARGS: return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_ARG_SIZE: return "CL_INVALID_ARG_SIZE";
    case CL_INVALID_ARG_INDEX: return "CL_INVALID_ARG_INDEX";
    case CL_INVALID_WORK_GROUP_SIZE: return "CL_INVALID_WORK_GROUP_SIZE";
    case CL_INVALID_KERNEL_NAME: return "CL_INVALID_KERNEL_NAME";
    case CL_INVALID_MEM_OBJECT: return "CL_INVALID_MEM_OBJECT";
    default: return "OpenCL error " + std::to_string(code);
  }
}

}  // namespace mc::compute
