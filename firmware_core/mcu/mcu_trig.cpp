// mcu_sincosf (mcu_trig.h): the core's float sin and cos, for C callers in the images.
#include "mcu_trig.h"

#include "planar/kernel_trig.hpp"

extern "C" void mcu_sincosf(float x, float *s, float *c) { legsim::sincos_reduced(x, *s, *c); }
