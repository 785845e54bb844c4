// Pictures of the window: the default framebuffer read back, flipped to rows
// from the top, written as PNG.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace mc::viewer {

struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // rows from the top
};

// The back buffer as drawn so far this frame (call before swapping).
Picture read_back_buffer(int width, int height);

// Throws std::runtime_error when the file cannot be written.
void write_png(const std::filesystem::path& path, const Picture& p);

}  // namespace mc::viewer
