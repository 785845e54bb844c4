// png_ink FILE X0 Y0 X1 Y1: the pixels of a PNG that are not white (any
// channel below 250) in the box [X0, X1) x [Y0, Y1), clipped to the
// picture; prints "WIDTH HEIGHT INK". For tests/no_font.sh, which checks
// that text was drawn where a picture's title goes.
#include <algorithm>
#include <cstdio>
#include <cstdlib>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: png_ink FILE X0 Y0 X1 Y1\n");
    return 2;
  }
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(argv[1], &w, &h, &n, 3);
  if (!px) {
    std::fprintf(stderr, "png_ink: %s: %s\n", argv[1], stbi_failure_reason());
    return 1;
  }
  const int x0 = std::max(0, std::atoi(argv[2])), y0 = std::max(0, std::atoi(argv[3]));
  const int x1 = std::min(w, std::atoi(argv[4])), y1 = std::min(h, std::atoi(argv[5]));
  long ink = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char* p = px + (static_cast<long>(y) * w + x) * 3;
      ink += p[0] < 250 || p[1] < 250 || p[2] < 250;
    }
  stbi_image_free(px);
  std::printf("%d %d %ld\n", w, h, ink);
  return 0;
}
