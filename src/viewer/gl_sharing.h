// The OpenCL context properties that name the window's GL context, for
// CL-GL sharing (cl_khr_gl_sharing): on X11, the GLX context and display.
#pragma once

#include <string>
#include <vector>

#include "compute/context.h"
#include "viewer/gl.h"

namespace mc::viewer {

// Empty when the window's context is not a GLX one (Wayland/EGL).
std::vector<cl_context_properties> gl_sharing_properties(GLFWwindow* window);

// Whether the GL driver (its GL_VENDOR and GL_RENDERER strings) and the
// OpenCL platform (its name) are one vendor's: sharing hands the GL context
// to the CL driver, and another vendor's driver cannot take it (NVIDIA's
// OpenCL given Mesa's software GLX context under Xvfb, say). Mesa's GL
// matches Mesa's OpenCL (rusticl, Clover); NVIDIA, AMD and Intel match
// their own.
bool same_gl_cl_vendor(const std::string& gl_vendor, const std::string& gl_renderer, const std::string& cl_platform);

}  // namespace mc::viewer
