// Occupancy images (ROS map_server convention) -> wall segments.
#if CAIRN_SIM_HAVE_PNG
#include <png.h>
#endif

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <sstream>

#include "cairn/sim/world.hpp"

namespace cairn::sim {
namespace {

// Larger images are refused before anything is allocated (about 20000 x 20000 pixels: 1 km square at 5 cm).
constexpr long long kMaxImagePixels = 400'000'000;

void checkImageSize(const std::string& path, long long width, long long height) {
  if (width <= 0 || height <= 0 || width > 100000 || height > 100000)
    throw InputError(path, 0, "bad image size " + std::to_string(width) + " x " + std::to_string(height));
  if (width * height > kMaxImagePixels)
    throw InputError(path, 0, "image of " + std::to_string(width) + " x " + std::to_string(height) +
                                  " pixels is larger than " + std::to_string(kMaxImagePixels) + " pixels");
}

OccupancyImage readPgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open image");
  std::string magic;
  in >> magic;
  auto token = [&]() -> long {
    // skips whitespace and # comments
    for (;;) {
      int c = in.peek();
      if (c == '#') {
        std::string dummy;
        std::getline(in, dummy);
      } else if (std::isspace(c)) {
        in.get();
      } else {
        break;
      }
    }
    long v = -1;
    if (!(in >> v)) throw InputError(path, 0, "truncated PGM header");
    return v;
  };
  if (magic != "P5" && magic != "P2") throw InputError(path, 0, "not a PGM (P2/P5) image");
  OccupancyImage img;
  img.width = static_cast<int>(token());
  img.height = static_cast<int>(token());
  const long maxval = token();
  checkImageSize(path, img.width, img.height);
  if (maxval <= 0 || maxval > 65535) throw InputError(path, 0, "bad PGM maxval");
  const std::size_t n = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
  if (magic == "P5") in.get();  // single whitespace after maxval
  const int bytes = maxval > 255 ? 2 : 1;
  // The header's size against the data the file has, before allocating: binary pixels take `bytes` each,
  // text pixels at least two characters (a digit and a separator) but the last.
  const std::streamoff data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff data_size = in.tellg() - data_start;
  in.seekg(data_start);
  const std::size_t needed = magic == "P5" ? n * static_cast<std::size_t>(bytes) : 2 * n - 1;
  if (data_start < 0 || data_size < 0 || static_cast<std::size_t>(data_size) < needed)
    throw InputError(path, 0, "truncated PGM data: the header says " + std::to_string(img.width) + " x " +
                                  std::to_string(img.height) + " pixels, the file has " +
                                  std::to_string(std::max<std::streamoff>(data_size, 0)) + " data bytes");
  img.pixels.resize(n);
  if (magic == "P5") {
    std::vector<unsigned char> raw(n * static_cast<std::size_t>(bytes));
    if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size())))
      throw InputError(path, 0, "truncated PGM data");
    for (std::size_t i = 0; i < n; ++i) {
      const long v = bytes == 2 ? (raw[2 * i] << 8) | raw[2 * i + 1] : raw[i];
      img.pixels[i] = static_cast<std::uint8_t>(v * 255 / maxval);
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      long v = -1;
      if (!(in >> v) || v < 0 || v > maxval) throw InputError(path, 0, "bad PGM pixel value");
      img.pixels[i] = static_cast<std::uint8_t>(v * 255 / maxval);
    }
  }
  return img;
}

#if CAIRN_SIM_HAVE_PNG
OccupancyImage readPng(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str()))
    throw InputError(path, 0, std::string("cannot read PNG: ") + image.message);
  image.format = PNG_FORMAT_GRAY;
  try {
    checkImageSize(path, image.width, image.height);  // a few compressed bytes can claim any size
  } catch (...) {
    png_image_free(&image);
    throw;
  }
  OccupancyImage img;
  img.width = static_cast<int>(image.width);
  img.height = static_cast<int>(image.height);
  img.pixels.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, img.pixels.data(), 0, nullptr)) {
    const std::string msg = image.message;
    png_image_free(&image);
    throw InputError(path, 0, "cannot decode PNG: " + msg);
  }
  return img;
}
#endif

}  // namespace

OccupancyImage readImage(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open image");
  unsigned char sig[8] = {};
  in.read(reinterpret_cast<char*>(sig), 8);
  static const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() == 8 && std::equal(sig, sig + 8, kPngSignature)) {
#if CAIRN_SIM_HAVE_PNG
    return readPng(path);
#else
    throw InputError(path, 0, "PNG image, but cairn_sim was built without libpng (install libpng-dev)");
#endif
  }
  return readPgm(path);
}

std::vector<Segment> occupancyToSegments(const OccupancyImage& img, double resolution, Pose2 origin,
                                         double occupied_thresh, bool negate, float reflectivity) {
  const int w = img.width, h = img.height;
  // occ(cx, cy) with cy counted upwards from the bottom row (map frame), outside = free
  std::vector<std::uint8_t> occ(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const double v = img.pixels[static_cast<std::size_t>(r) * w + c];
      const double p = negate ? v / 255.0 : (255.0 - v) / 255.0;
      occ[static_cast<std::size_t>(h - 1 - r) * w + c] = p > occupied_thresh ? 1 : 0;
    }
  auto at = [&](int cx, int cy) -> int {
    if (cx < 0 || cy < 0 || cx >= w || cy >= h) return 0;
    return occ[static_cast<std::size_t>(cy) * w + cx];
  };
  auto corner = [&](double gx, double gy) { return transformPoint(origin, {gx * resolution, gy * resolution}); };
  std::vector<Segment> out;
  // horizontal grid lines y = gy: edge between cell rows gy-1 and gy where occupancy differs
  for (int gy = 0; gy <= h; ++gy) {
    int run_start = -1, run_kind = 0;
    for (int cx = 0; cx <= w; ++cx) {
      const int below = at(cx, gy - 1), above = at(cx, gy);
      const int kind = cx < w && below != above ? (below ? 1 : 2) : 0;  // orientation kept apart
      if (kind != run_kind) {
        if (run_kind) out.push_back({corner(run_start, gy), corner(cx, gy), reflectivity});
        run_start = cx;
        run_kind = kind;
      }
    }
  }
  for (int gx = 0; gx <= w; ++gx) {
    int run_start = -1, run_kind = 0;
    for (int cy = 0; cy <= h; ++cy) {
      const int left = at(gx - 1, cy), right = at(gx, cy);
      const int kind = cy < h && left != right ? (left ? 1 : 2) : 0;
      if (kind != run_kind) {
        if (run_kind) out.push_back({corner(gx, run_start), corner(gx, cy), reflectivity});
        run_start = cy;
        run_kind = kind;
      }
    }
  }
  return out;
}

}  // namespace cairn::sim
