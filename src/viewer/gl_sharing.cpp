#include "viewer/gl_sharing.h"

#include <cctype>

// GLFW's native access (glfw3native.h with GLFW_EXPOSE_NATIVE_X11/GLX) would
// pull in Xlib, GLX and the Xrandr headers (libxrandr-dev) for two functions;
// they are declared here with the same opaque types instead
// (Display = struct _XDisplay, GLXContext = struct __GLXcontextRec*).
extern "C" {
struct _XDisplay;
struct __GLXcontextRec;
_XDisplay* glfwGetX11Display(void);
__GLXcontextRec* glfwGetGLXContext(GLFWwindow* window);
}

namespace mc::viewer {

std::vector<cl_context_properties> gl_sharing_properties(GLFWwindow* window) {
  __GLXcontextRec* glx = glfwGetGLXContext(window);
  _XDisplay* display = glfwGetX11Display();
  if (glx == nullptr || display == nullptr) return {};
  return {CL_GL_CONTEXT_KHR, reinterpret_cast<cl_context_properties>(glx), CL_GLX_DISPLAY_KHR,
          reinterpret_cast<cl_context_properties>(display)};
}

namespace {
std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
}  // namespace

bool same_gl_cl_vendor(const std::string& gl_vendor, const std::string& gl_renderer, const std::string& cl_platform) {
  const std::string gl = lower(gl_vendor + " " + gl_renderer), cl = lower(cl_platform);
  struct Vendor {
    const char* gl;
    std::vector<const char*> cl;
  };
  const Vendor vendors[] = {{"nvidia", {"nvidia"}},
                            {"mesa", {"rusticl", "clover", "mesa"}},
                            {"amd", {"amd", "advanced micro devices"}},
                            {"intel", {"intel"}}};
  for (const Vendor& v : vendors) {
    if (gl.find(v.gl) == std::string::npos) continue;
    for (const char* name : v.cl)
      if (cl.find(name) != std::string::npos) return true;
    return false;  // the first vendor the GL strings name decides
  }
  return false;
}

}  // namespace mc::viewer
