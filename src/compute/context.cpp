#include "compute/context.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

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

int platform_count() {
  cl_uint n = 0;
  if (clGetPlatformIDs(0, nullptr, &n) != CL_SUCCESS) return 0;
  return static_cast<int>(n);
}

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
      i.platform_vendor = platforms[p].getInfo<CL_PLATFORM_VENDOR>();
      i.name = devices[d].getInfo<CL_DEVICE_NAME>();
      i.vendor = devices[d].getInfo<CL_DEVICE_VENDOR>();
      i.type = type_name(devices[d].getInfo<CL_DEVICE_TYPE>());
      i.version = devices[d].getInfo<CL_DEVICE_VERSION>();
      i.c_version = devices[d].getInfo<CL_DEVICE_OPENCL_C_VERSION>();
      const std::string ext = devices[d].getInfo<CL_DEVICE_EXTENSIONS>();
      i.fp64 = ext.find("cl_khr_fp64") != std::string::npos;
      i.gl_sharing = ext.find("cl_khr_gl_sharing") != std::string::npos;
      i.global_mem_bytes = devices[d].getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
      i.max_alloc_bytes = devices[d].getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
      i.compute_units = static_cast<int>(devices[d].getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
      // Strip the padding some drivers leave in names.
      for (std::string* t : {&i.platform_name, &i.platform_vendor, &i.name, &i.vendor, &i.version, &i.c_version})
        while (!t->empty() && (t->back() == ' ' || t->back() == '\0')) t->pop_back();
      out.push_back(std::move(f));
    }
  }
  return out;
}

// The short names of implementations and vendors, and the words (lower
// case) each looks for in the platform's name and vendor, then the device's.
struct ShortName {
  const char* name;
  std::vector<std::string> words;
};
const ShortName kShortNames[] = {
    {"pocl", {"portable computing language", "pocl"}},  // vendor "The pocl project"
    {"nvidia", {"nvidia"}},                               // platform "NVIDIA CUDA"
    {"cuda", {"nvidia", "cuda"}},
    {"amd", {"amd", "advanced micro devices"}},           // "AMD Accelerated Parallel Processing"
    {"intel", {"intel"}},                                 // "Intel(R) OpenCL", "Intel(R) Corporation"
    {"rusticl", {"rusticl"}},                             // Mesa's, vendor "Mesa/X.org"
    {"mesa", {"mesa", "rusticl", "clover"}},              // rusticl or Clover
};

Found pick(const std::string& spec_in) {
  const std::vector<Found> all = enumerate();
  if (all.empty()) throw Error(no_device_message());
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
      // A short name looks for its words in the platform's name and vendor,
      // then in the device's; any other spec in the device's or platform's
      // name, then in their vendors.
      std::vector<std::string> words = {spec};
      bool short_name = false;
      for (const ShortName& n : kShortNames)
        if (spec == n.name) words.assign(n.words.begin(), n.words.end()), short_name = true;
      auto has = [&](const std::string& text) {
        const std::string t = lower(text);
        return std::any_of(words.begin(), words.end(), [&](const std::string& w) { return t.find(w) != std::string::npos; });
      };
      for (int pass = 0; pass < 2; ++pass)
        for (const Found& f : all) {
          const DeviceInfo& i = f.info;
          const bool hit = short_name ? (pass == 0 ? has(i.platform_name) || has(i.platform_vendor)
                                                   : has(i.name) || has(i.vendor))
                                      : (pass == 0 ? has(i.name) || has(i.platform_name)
                                                   : has(i.vendor) || has(i.platform_vendor));
          if (hit) return f;
        }
    }
  }
  std::ostringstream msg;
  msg << "--device '" << spec_in << "' matches no OpenCL device; available:";
  for (const Found& f : all) msg << "\n  " << f.info.label();
  for (const auto& [index, name] : platforms_without_devices()) {
    msg << "\n  platform " << index << " (" << name << "): no devices";
    if (lower(name) == "rusticl") msg << " (RUSTICL_ENABLE=llvmpipe makes it offer its CPU device)";
  }
  msg << "\nuse auto, gpu, cpu, accelerator, P:D, a short name (";
  for (std::size_t k = 0; k < std::size(kShortNames); ++k) msg << (k ? ", " : "") << kShortNames[k].name;
  msg << ") or part of a device or platform name";
  throw Error(msg.str());
}

}  // namespace

std::string DeviceInfo::label() const {
  std::ostringstream s;
  s << platform_index << ':' << device_index << ' ' << name << " (" << type << ", "
    << platform_name << ')';
  return s.str();
}

std::string no_device_message() {
  std::string m;
  const int platforms = platform_count();
  if (platforms == 0)
    m = "no OpenCL platform found";
  else
    m = "no OpenCL device found (" + std::to_string(platforms) + " platform" + (platforms == 1 ? "" : "s") +
        " without devices)";
  m += ": install an OpenCL driver (on Debian `sudo apt-get install pocl-opencl-icd` for the CPU, or your GPU "
       "vendor's OpenCL driver), then check that `millcharge devices` or `clinfo -l` lists a device";
  if (const char* v = std::getenv("OCL_ICD_VENDORS"); v && *v)
    m += std::string("; OCL_ICD_VENDORS is set to '") + v + "': unset it to use the drivers in /etc/OpenCL/vendors";
  return m;
}

std::vector<DeviceInfo> list_devices() {
  std::vector<DeviceInfo> out;
  for (const Found& f : enumerate()) out.push_back(f.info);
  return out;
}

DeviceInfo choose_device(const std::string& spec) { return pick(spec).info; }

std::vector<std::string> device_short_names() {
  std::vector<std::string> out;
  for (const ShortName& n : kShortNames) out.push_back(n.name);
  return out;
}

std::vector<std::pair<int, std::string>> platforms_without_devices() {
  std::vector<std::pair<int, std::string>> out;
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    return out;
  }
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      devices.clear();  // CL_DEVICE_NOT_FOUND
    }
    if (devices.empty()) out.emplace_back(static_cast<int>(p), platforms[p].getInfo<CL_PLATFORM_NAME>());
  }
  return out;
}

struct Context::Ledger {
  std::atomic<std::size_t> allocated{0};
};

namespace {

// "512M", "2G", "1048576" → bytes; 0 when unset or not a size.
std::size_t memory_override() {
  const char* env = std::getenv("MILLCHARGE_DEVICE_MEMORY");
  if (!env || !*env) return 0;
  char* end = nullptr;
  const double v = std::strtod(env, &end);
  double scale = 1;
  if (end && *end) {
    switch (std::toupper(static_cast<unsigned char>(*end))) {
      case 'K': scale = 1024.0; break;
      case 'M': scale = 1024.0 * 1024; break;
      case 'G': scale = 1024.0 * 1024 * 1024; break;
      default: throw Error(std::string("MILLCHARGE_DEVICE_MEMORY='") + env + "': expected bytes, e.g. 512M or 2G");
    }
  }
  if (!(v > 0) || v * scale > 1e18)
    throw Error(std::string("MILLCHARGE_DEVICE_MEMORY='") + env + "': expected bytes, e.g. 512M or 2G");
  return static_cast<std::size_t>(v * scale);
}

}  // namespace

// The device from a spec (or MILLCHARGE_DEVICE), and the memory a run may use.
void Context::choose(const std::string& spec_in) {
  std::string spec = spec_in;
  if (spec.empty())
    if (const char* env = std::getenv("MILLCHARGE_DEVICE")) spec = env;
  Found f = pick(spec);
  info_ = f.info;
  device_ = f.device;
  memory_bytes_ = info_.global_mem_bytes;
  if (const std::size_t limit = memory_override(); limit > 0) memory_bytes_ = std::min(memory_bytes_, limit);
}

namespace {
unsigned char fill_from_environment() {
  const char* p = std::getenv("MILLCHARGE_POISON");
  return p && std::string(p) == "1" ? 0xFF : 0x00;
}
}  // namespace

Context::Context(const std::string& spec_in) : ledger_(std::make_shared<Ledger>()) {
  new_buffer_fill_ = fill_from_environment();
  choose(spec_in);
  try {
    context_ = cl::Context(device_);
    queue_ = cl::CommandQueue(context_, device_);
  } catch (const cl::Error& e) {
    throw Error("could not open OpenCL device " + info_.label() + ": " + e.what() +
                " (" + error_name(e.err()) + ")");
  }
}

Context::Context(const std::string& spec_in, const std::vector<cl_context_properties>& gl_properties)
    : ledger_(std::make_shared<Ledger>()) {
  new_buffer_fill_ = fill_from_environment();
  choose(spec_in);
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
    throw error(std::string("OpenCL queue failed: ") + e.what(), e.err());
  }
}

std::size_t Context::allocated_bytes() const { return ledger_->allocated.load(); }

std::size_t Context::max_alloc_bytes() const {
  return std::min(info_.max_alloc_bytes > 0 ? info_.max_alloc_bytes : memory_bytes_, memory_bytes_);
}

std::shared_ptr<void> Context::reserve(std::size_t bytes, const std::string& label) {
  if (bytes > max_alloc_bytes()) {
    std::ostringstream m;
    m << "device out of memory: buffer '" << label << "' needs " << bytes_text(bytes) << " in one piece, but "
      << info_.label() << " allows at most " << bytes_text(max_alloc_bytes())
      << " per buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE); " << kOutOfMemoryFix;
    throw Error(m.str());
  }
  const std::size_t before = ledger_->allocated.load();
  if (bytes > memory_bytes_ || before > memory_bytes_ - bytes) {
    std::ostringstream m;
    m << "device out of memory: the run needs at least " << bytes_text(before + bytes) << " but " << info_.label()
      << " has " << bytes_text(memory_bytes_)
      << (memory_bytes_ < info_.global_mem_bytes ? " (set by MILLCHARGE_DEVICE_MEMORY)" : "")
      << "; buffer '" << label << "' of " << bytes_text(bytes) << " did not fit on top of " << bytes_text(before)
      << " already allocated; " << kOutOfMemoryFix;
    throw Error(m.str());
  }
  ledger_->allocated += bytes;
  std::shared_ptr<Ledger> ledger = ledger_;
  return std::shared_ptr<void>(nullptr, [ledger, bytes](void*) { ledger->allocated -= bytes; });
}

Error Context::error(const std::string& what, int code) const {
  if (!is_out_of_memory(code)) return Error(what + ": " + error_name(code));
  std::ostringstream m;
  m << "device out of memory (" << (code == CL_MEM_OBJECT_ALLOCATION_FAILURE ? "CL_MEM_OBJECT_ALLOCATION_FAILURE"
                                    : code == CL_OUT_OF_RESOURCES            ? "CL_OUT_OF_RESOURCES"
                                                                             : "CL_OUT_OF_HOST_MEMORY")
    << ") " << what << ": the run's buffers take " << bytes_text(allocated_bytes()) << " of the "
    << bytes_text(memory_bytes_) << " that " << info_.label() << " has; " << kOutOfMemoryFix;
  return Error(m.str());
}

bool is_out_of_memory(int code) {
  return code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES || code == CL_OUT_OF_HOST_MEMORY;
}

std::string bytes_text(std::size_t bytes) {
  char buf[96];
  const double b = static_cast<double>(bytes);
  if (b >= 1024.0 * 1024 * 1024) std::snprintf(buf, sizeof buf, "%.2f GiB", b / (1024.0 * 1024 * 1024));
  else if (b >= 1024.0 * 1024) std::snprintf(buf, sizeof buf, "%.1f MiB", b / (1024.0 * 1024));
  else if (b >= 1024.0) std::snprintf(buf, sizeof buf, "%.1f KiB", b / 1024.0);
  else std::snprintf(buf, sizeof buf, "%zu bytes", bytes);
  return std::string(buf) + (bytes >= 1024 ? " (" + std::to_string(bytes) + " bytes)" : "");
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
