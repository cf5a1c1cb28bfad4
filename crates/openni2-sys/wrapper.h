/* bindgen entry point: OpenNI2's C API. */
#include <OniCAPI.h>
