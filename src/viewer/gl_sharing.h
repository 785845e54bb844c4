// The OpenCL context properties that name the window's GL context, for
// CL-GL sharing (cl_khr_gl_sharing): on X11, the GLX context and display.
#pragma once

#include <vector>

#include "compute/context.h"
#include "viewer/gl.h"

namespace mc::viewer {

// Empty when the window's context is not a GLX one (Wayland/EGL).
std::vector<cl_context_properties> gl_sharing_properties(GLFWwindow* window);

}  // namespace mc::viewer
