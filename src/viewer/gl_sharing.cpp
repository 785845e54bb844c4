#include "viewer/gl_sharing.h"

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

}  // namespace mc::viewer
