#include "viewer/screenshot.h"

#include <cstring>
#include <stdexcept>
#include <string>

#include "io/atomic_file.h"
#include "viewer/gl.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>

namespace mc::viewer {

Picture read_back_buffer(int width, int height) {
  Picture p;
  p.width = width;
  p.height = height;
  std::vector<std::uint8_t> bottom_up(static_cast<std::size_t>(width) * height * 3);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  p.rgb.resize(bottom_up.size());
  const std::size_t row = static_cast<std::size_t>(width) * 3;
  for (int y = 0; y < height; ++y)
    std::memcpy(&p.rgb[static_cast<std::size_t>(y) * row], &bottom_up[static_cast<std::size_t>(height - 1 - y) * row],
                row);
  return p;
}

void write_png(const std::filesystem::path& path, const Picture& p) {
  std::string bytes;
  auto sink = [](void* ctx, void* data, int size) {
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
  };
  if (!stbi_write_png_to_func(sink, &bytes, p.width, p.height, 3, p.rgb.data(), p.width * 3))
    throw std::runtime_error("cannot encode " + path.string());
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  io::write_file_atomic(path, bytes);
}

}  // namespace mc::viewer
