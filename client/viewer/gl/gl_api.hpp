#pragma once
// OpenGL 3.3 core declarations. On Linux libGL (glvnd) exports every core entry point, so the
// prototypes come straight from the Khronos header and no loader is needed. Include this
// before GLFW (which must then be included with GLFW_INCLUDE_NONE).
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
