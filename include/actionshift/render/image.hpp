#pragma once
/// \file
/// RGB images, their PNG (libpng) and animated GIF (giflib) files, a 5x7 bitmap font for overlays,
/// and side-by-side montages.

#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

namespace actionshift::render {

/// 8-bit RGB colour.
struct Rgb {
  std::uint8_t r{0}, g{0}, b{0};
  bool operator==(const Rgb&) const = default;
};

/// An 8-bit RGB image, row-major, origin top-left.
class Image {
 public:
  Image() = default;
  /// A `width` x `height` image filled with `fill`. Throws std::invalid_argument for a size <= 0.
  Image(int width, int height, Rgb fill = {});
  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return width_ == 0; }
  /// Pixel (x, y); x in [0, width), y in [0, height) (unchecked).
  Rgb at(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x));
    return {pixels_[i], pixels_[i + 1], pixels_[i + 2]};
  }
  /// Set pixel (x, y); ignored outside the image.
  void set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x));
    pixels_[i] = c.r;
    pixels_[i + 1] = c.g;
    pixels_[i + 2] = c.b;
  }
  const std::vector<std::uint8_t>& pixels() const { return pixels_; }  ///< RGBRGB..., 3 * width * height bytes
  std::vector<std::uint8_t>& mutable_pixels() { return pixels_; }
  bool operator==(const Image&) const = default;

 private:
  int width_{0}, height_{0};
  std::vector<std::uint8_t> pixels_;
};

/// Width in pixels of `text` drawn with draw_text at `scale`.
int text_width(std::string_view text, int scale = 1);
/// Draw `text` (ASCII; lower case is drawn upper case; unknown characters as blanks) with the 5x7
/// font, top-left corner at (x, y), each font pixel `scale` x `scale` image pixels.
void draw_text(Image& image, int x, int y, std::string_view text, Rgb color, int scale = 1);
/// Darken a rectangle (the background of an overlay line), alpha in [0, 1] of black.
void shade_rect(Image& image, int x0, int y0, int x1, int y1, double alpha);

/// Write a PNG (RGB, 8 bit). Throws actionshift::InputError(path, "out", reason) if it cannot be written.
void write_png(const std::filesystem::path& path, const Image& image);

/// Write an animated GIF that loops forever, `delay_cs` hundredths of a second per frame; each frame
/// gets its own 256-colour palette (giflib's median-cut quantiser). All frames must have the first
/// frame's size. Throws actionshift::InputError(path, "out", reason) if it cannot be written and
/// std::invalid_argument for no frames or mismatched sizes.
void write_gif(const std::filesystem::path& path, const std::vector<Image>& frames, int delay_cs = 10);

/// Frames of a GIF file (each composited to full RGB). Throws actionshift::InputError(path, "", reason).
std::vector<Image> read_gif(const std::filesystem::path& path);

/// Images placed left to right with a `gap`-pixel separator of `background`, top-aligned.
Image side_by_side(const std::vector<Image>& images, int gap = 4, Rgb background = {255, 255, 255});

}  // namespace actionshift::render
