// images: PNG (libpng), animated GIF (giflib), the 5x7 overlay font, montages
#include "actionshift/core/input_file.hpp"
#include "actionshift/render/image.hpp"

#include "actionshift/core/error.hpp"

#include <fcntl.h>
#include <gif_lib.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

namespace actionshift::render {

Image::Image(int width, int height, Rgb fill) : width_(width), height_(height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("image size " + std::to_string(width) + "x" + std::to_string(height) + " is not positive");
  pixels_.resize(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (std::size_t i = 0; i < pixels_.size(); i += 3) {
    pixels_[i] = fill.r;
    pixels_[i + 1] = fill.g;
    pixels_[i + 2] = fill.b;
  }
}

// ---- 5x7 font: 7 rows per glyph, bit 4 = leftmost column

namespace {

using Glyph = std::array<std::uint8_t, 7>;

const Glyph* glyph(char ch) {
  static const std::array<std::pair<char, Glyph>, 50> kFont{{
      {'0', {0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110}},
      {'1', {0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
      {'2', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111}},
      {'3', {0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110}},
      {'4', {0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010}},
      {'5', {0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110}},
      {'6', {0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110}},
      {'7', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000}},
      {'8', {0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110}},
      {'9', {0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100}},
      {'A', {0b01110, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
      {'B', {0b11110, 0b10001, 0b10001, 0b11110, 0b10001, 0b10001, 0b11110}},
      {'C', {0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110}},
      {'D', {0b11100, 0b10010, 0b10001, 0b10001, 0b10001, 0b10010, 0b11100}},
      {'E', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111}},
      {'F', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000}},
      {'G', {0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111}},
      {'H', {0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
      {'I', {0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
      {'J', {0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100}},
      {'K', {0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001}},
      {'L', {0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111}},
      {'M', {0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001}},
      {'N', {0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001}},
      {'O', {0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
      {'P', {0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000}},
      {'Q', {0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101}},
      {'R', {0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001}},
      {'S', {0b01111, 0b10000, 0b10000, 0b01110, 0b00001, 0b00001, 0b11110}},
      {'T', {0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100}},
      {'U', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
      {'V', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100}},
      {'W', {0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010}},
      {'X', {0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001}},
      {'Y', {0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100}},
      {'Z', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111}},
      {'/', {0b00001, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b10000}},
      {':', {0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000}},
      {'.', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100}},
      {',', {0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b00100, 0b01000}},
      {'-', {0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000}},
      {'_', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b11111}},
      {'(', {0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010}},
      {')', {0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000}},
      {'=', {0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000}},
      {'%', {0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011}},
      {'#', {0b01010, 0b01010, 0b11111, 0b01010, 0b11111, 0b01010, 0b01010}},
      {'+', {0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000}},
      {'>', {0b01000, 0b00100, 0b00010, 0b00001, 0b00010, 0b00100, 0b01000}},
      {'<', {0b00010, 0b00100, 0b01000, 0b10000, 0b01000, 0b00100, 0b00010}},
  }};
  if (ch >= 'a' && ch <= 'z') ch = static_cast<char>(ch - 'a' + 'A');
  for (const auto& [c, g] : kFont)
    if (c == ch) return &g;
  return nullptr;
}

}  // namespace

int text_width(std::string_view text, int scale) { return static_cast<int>(text.size()) * 6 * scale; }

void draw_text(Image& image, int x, int y, std::string_view text, Rgb color, int scale) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const Glyph* g = glyph(text[i]);
    if (!g) continue;
    const int gx = x + static_cast<int>(i) * 6 * scale;
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col)
        if ((*g)[static_cast<std::size_t>(row)] & (1u << (4 - col)))
          for (int dy = 0; dy < scale; ++dy)
            for (int dx = 0; dx < scale; ++dx) image.set(gx + col * scale + dx, y + row * scale + dy, color);
  }
}

void shade_rect(Image& image, int x0, int y0, int x1, int y1, double alpha) {
  x0 = std::max(0, x0);
  y0 = std::max(0, y0);
  x1 = std::min(image.width(), x1);
  y1 = std::min(image.height(), y1);
  const double k = 1.0 - std::clamp(alpha, 0.0, 1.0);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const Rgb c = image.at(x, y);
      image.set(x, y, {static_cast<std::uint8_t>(c.r * k), static_cast<std::uint8_t>(c.g * k), static_cast<std::uint8_t>(c.b * k)});
    }
}

// ---- PNG

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};

std::unique_ptr<std::FILE, FileCloser> open_for_writing(const std::filesystem::path& path) {
  require_replaceable_output(path.string());  // fopen of a FIFO would block, of /dev/full write nowhere
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "wb"));
  if (!f) throw InputError(path.string(), "out", "cannot write file");
  return f;
}

}  // namespace

void write_png(const std::filesystem::path& path, const Image& image) {
  if (image.empty()) throw std::invalid_argument("write_png: empty image");
  auto f = open_for_writing(path);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng could not allocate its write structures");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw InputError(path.string(), "out", "libpng failed while writing");
  }
  png_init_io(png, f.get());
  png_set_compression_level(png, 6);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width()), static_cast<png_uint_32>(image.height()), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height(); ++y)
    png_write_row(png, image.pixels().data() + 3 * static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width()));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(f.get()) != 0 || std::ferror(f.get())) throw InputError(path.string(), "out", "write failed");
}

// ---- GIF

void write_gif(const std::filesystem::path& path, const std::vector<Image>& frames, int delay_cs) {
  if (frames.empty() || frames.front().empty()) throw std::invalid_argument("write_gif: no frames");
  const int w = frames.front().width(), h = frames.front().height();
  for (const Image& f : frames)
    if (f.width() != w || f.height() != h) throw std::invalid_argument("write_gif: frames of different sizes");
  // open the file ourselves: giflib's EGifOpenFileName creates it with mode 0600
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
  if (fd < 0) throw InputError(path.string(), "out", "cannot write file");
  int err = 0;
  GifFileType* gif = EGifOpenFileHandle(fd, &err);
  if (!gif) {
    ::close(fd);
    throw InputError(path.string(), "out", std::string("cannot write file (") + GifErrorString(err) + ")");
  }
  auto fail = [&](const char* what) {
    int close_err = 0;
    EGifCloseFile(gif, &close_err);
    throw InputError(path.string(), "out", std::string("giflib: ") + what);
  };
  EGifSetGifVersion(gif, true);
  if (EGifPutScreenDesc(gif, w, h, 8, 0, nullptr) == GIF_ERROR) fail("screen descriptor");
  // NETSCAPE2.0 application extension: loop forever
  const GifByteType app[] = {'N', 'E', 'T', 'S', 'C', 'A', 'P', 'E', '2', '.', '0'};
  const GifByteType loop[] = {1, 0, 0};
  if (EGifPutExtensionLeader(gif, APPLICATION_EXT_FUNC_CODE) == GIF_ERROR ||
      EGifPutExtensionBlock(gif, sizeof app, app) == GIF_ERROR || EGifPutExtensionBlock(gif, sizeof loop, loop) == GIF_ERROR ||
      EGifPutExtensionTrailer(gif) == GIF_ERROR)
    fail("loop extension");
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  std::vector<GifByteType> r(n), g(n), b(n), index(n);
  for (const Image& f : frames) {
    const auto& px = f.pixels();
    for (std::size_t i = 0; i < n; ++i) {
      r[i] = px[3 * i];
      g[i] = px[3 * i + 1];
      b[i] = px[3 * i + 2];
    }
    int colors = 256;
    std::array<GifColorType, 256> palette{};
    if (GifQuantizeBuffer(static_cast<unsigned>(w), static_cast<unsigned>(h), &colors, r.data(), g.data(), b.data(),
                          index.data(), palette.data()) == GIF_ERROR)
      fail("colour quantisation");
    ColorMapObject* map = GifMakeMapObject(256, palette.data());
    if (!map) fail("colour map");
    GraphicsControlBlock gcb{};
    gcb.DisposalMode = DISPOSE_DO_NOT;
    gcb.DelayTime = delay_cs;
    gcb.TransparentColor = NO_TRANSPARENT_COLOR;
    GifByteType ext[4];
    const std::size_t len = EGifGCBToExtension(&gcb, ext);
    const bool ok = EGifPutExtension(gif, GRAPHICS_EXT_FUNC_CODE, static_cast<int>(len), ext) != GIF_ERROR &&
                    EGifPutImageDesc(gif, 0, 0, w, h, false, map) != GIF_ERROR;
    GifFreeMapObject(map);
    if (!ok) fail("frame header");
    for (int y = 0; y < h; ++y)
      if (EGifPutLine(gif, index.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w), w) == GIF_ERROR)
        fail("frame data");
  }
  if (EGifCloseFile(gif, &err) == GIF_ERROR)
    throw InputError(path.string(), "out", std::string("cannot finish file (") + GifErrorString(err) + ")");
}

namespace {

// Walks a GIF's blocks (header, logical screen, extensions, image descriptors) before giflib decodes
// it, and refuses a screen above kMaxGifSide or an image outside its screen: giflib sizes an image's
// raster as a signed int width x height, which wraps at 46341 x 46341 and then writes past the
// buffer (a 35-byte file crashed montage).
constexpr int kMaxGifSide = 8192;

void check_gif_geometry(const std::string& bytes, const std::string& path) {
  auto fail = [&](const std::string& why) { throw InputError(path, "", "not a valid GIF (" + why + ")"); };
  auto u16 = [&](std::size_t i) {
    if (i + 2 > bytes.size()) fail("truncated");
    return static_cast<int>(static_cast<unsigned char>(bytes[i])) | (static_cast<int>(static_cast<unsigned char>(bytes[i + 1])) << 8);
  };
  auto byte = [&](std::size_t i) {
    if (i >= bytes.size()) fail("truncated");
    return static_cast<unsigned char>(bytes[i]);
  };
  auto skip_sub_blocks = [&](std::size_t i) {
    for (unsigned n = byte(i); n != 0; n = byte(i)) i += 1 + n;
    return i + 1;
  };
  if (bytes.size() < 13 || bytes.compare(0, 3, "GIF") != 0) fail("no GIF header");
  const int sw = u16(6), sh = u16(8);
  if (sw > kMaxGifSide || sh > kMaxGifSide)
    fail("screen " + std::to_string(sw) + "x" + std::to_string(sh) + " is larger than " + std::to_string(kMaxGifSide) + " pixels a side");
  std::size_t i = 13;
  if (byte(10) & 0x80) i += 3u * (2u << (byte(10) & 7));  // global colour table
  for (;;) {
    const unsigned char kind = byte(i);
    if (kind == 0x3B) return;  // trailer
    if (kind == 0x21) {        // extension: label, then sub-blocks
      i = skip_sub_blocks(i + 2);
    } else if (kind == 0x2C) {  // image descriptor
      const int left = u16(i + 1), top = u16(i + 3), w = u16(i + 5), h = u16(i + 7);
      if (left + w > sw || top + h > sh)
        fail("an image of " + std::to_string(w) + "x" + std::to_string(h) + " at (" + std::to_string(left) + ", " +
             std::to_string(top) + ") lies outside the " + std::to_string(sw) + "x" + std::to_string(sh) + " screen");
      const unsigned char flags = byte(i + 9);
      i += 10;
      if (flags & 0x80) i += 3u * (2u << (flags & 7));  // local colour table
      i = skip_sub_blocks(i + 1);                       // LZW minimum code size, then the data
    } else {
      fail("unknown block 0x" + std::string(1, "0123456789abcdef"[kind >> 4]) + std::string(1, "0123456789abcdef"[kind & 15]));
    }
  }
}

}  // namespace

std::vector<Image> read_gif(const std::filesystem::path& path) {
  check_gif_geometry(read_input_file(path.string(), "a GIF", std::uintmax_t{256} << 20), path.string());
  int err = 0;
  GifFileType* gif = DGifOpenFileName(path.c_str(), &err);
  if (!gif) throw InputError(path.string(), "", std::string("cannot read GIF (") + GifErrorString(err) + ")");
  std::unique_ptr<GifFileType, void (*)(GifFileType*)> guard(gif, [](GifFileType* p) {
    int e = 0;
    DGifCloseFile(p, &e);
  });
  if (DGifSlurp(gif) == GIF_ERROR) throw InputError(path.string(), "", std::string("not a valid GIF (") + GifErrorString(gif->Error) + ")");
  if (gif->SWidth <= 0 || gif->SHeight <= 0 || gif->ImageCount <= 0) throw InputError(path.string(), "", "GIF holds no image");
  std::vector<Image> frames;
  Image canvas(gif->SWidth, gif->SHeight);
  for (int k = 0; k < gif->ImageCount; ++k) {
    const SavedImage& im = gif->SavedImages[k];
    const ColorMapObject* map = im.ImageDesc.ColorMap ? im.ImageDesc.ColorMap : gif->SColorMap;
    if (!map) throw InputError(path.string(), "", "frame " + std::to_string(k) + " has no colour map");
    GraphicsControlBlock gcb{};
    gcb.TransparentColor = NO_TRANSPARENT_COLOR;
    DGifSavedExtensionToGCB(gif, k, &gcb);
    const auto& d = im.ImageDesc;
    for (int y = 0; y < d.Height; ++y)
      for (int x = 0; x < d.Width; ++x) {
        const int idx = im.RasterBits[static_cast<std::size_t>(y) * static_cast<std::size_t>(d.Width) + static_cast<std::size_t>(x)];
        if (idx == gcb.TransparentColor || idx >= map->ColorCount) continue;
        const GifColorType c = map->Colors[idx];
        canvas.set(d.Left + x, d.Top + y, {c.Red, c.Green, c.Blue});
      }
    frames.push_back(canvas);
  }
  return frames;
}

Image side_by_side(const std::vector<Image>& images, int gap, Rgb background) {
  if (images.empty()) throw std::invalid_argument("side_by_side: no images");
  int w = 0, h = 0;
  for (const Image& im : images) {
    w += im.width();
    h = std::max(h, im.height());
  }
  w += gap * static_cast<int>(images.size() - 1);
  Image out(w, h, background);
  int x0 = 0;
  for (const Image& im : images) {
    for (int y = 0; y < im.height(); ++y)
      for (int x = 0; x < im.width(); ++x) out.set(x0 + x, y, im.at(x, y));
    x0 += im.width() + gap;
  }
  return out;
}

}  // namespace actionshift::render
