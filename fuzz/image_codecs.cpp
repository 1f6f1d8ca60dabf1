// stb_image and tinyexr compiled from their Debian headers into the image harness, so that the
// sanitizers and the fuzzer's coverage see inside the decoders (the system libraries libstb.a and
// libtinyexr.so are built without them).
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>

#define TINYEXR_IMPLEMENTATION
#include <zlib.h>
#include <tinyexr.h>
