// OpenGL 3.3 core entry points for view/gl/. Linked directly from GLVND's libOpenGL (CMake's
// OpenGL::OpenGL), which dispatches to whichever vendor library made the context current (GLX for
// the GLFW window, EGL for the headless renderer), so no function loader is needed.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
