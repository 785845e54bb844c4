// The one include of OpenGL (through GLEW) and GLFW for the viewer: GLEW's
// header must come before any other GL header.
#pragma once

#include <GL/glew.h>
// GLEW first.
#include <GLFW/glfw3.h>
