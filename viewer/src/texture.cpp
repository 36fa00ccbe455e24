#include "texture.h"

#include <stb_image.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "strata/mesh_io.h"

namespace strata::viewer {

namespace {
// The next mipmap level: each pixel the mean of a 2x2 block (of the last row or column where the
// size is odd).
TextureLevel half(const TextureLevel& in) {
  TextureLevel out;
  out.width = std::max(1, in.width / 2);
  out.height = std::max(1, in.height / 2);
  out.rgba.resize(4 * static_cast<std::size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      const int x0 = std::min(2 * x, in.width - 1), x1 = std::min(2 * x + 1, in.width - 1);
      const int y0 = std::min(2 * y, in.height - 1), y1 = std::min(2 * y + 1, in.height - 1);
      auto at = [&](int px, int py, int c) {
        return static_cast<int>(in.rgba[4 * (static_cast<std::size_t>(py) * in.width + px) + c]);
      };
      for (int c = 0; c < 4; ++c)
        out.rgba[4 * (static_cast<std::size_t>(y) * out.width + x) + c] = static_cast<std::uint8_t>(
            (at(x0, y0, c) + at(x1, y0, c) + at(x0, y1, c) + at(x1, y1, c) + 2) / 4);
    }
  return out;
}
bool has_texcoords(const MeshAttributes& attributes) {
  return !attributes.texcoords.empty() || !attributes.corner_uv_index.empty();
}
}  // namespace

bool has_texture(const MeshAttributes& attributes) {
  return has_texcoords(attributes) && !face_texture_files(attributes).empty();
}

std::shared_ptr<const SceneTexture> make_scene_texture(const MeshAttributes& attributes,
                                                       const std::vector<Face>& faces) {
  const std::size_t num_faces = faces.size();
  if (!has_texcoords(attributes)) return nullptr;
  const std::vector<int> file_of_face = face_texture_files(attributes);  // as has_texture(), once
  if (file_of_face.empty()) return nullptr;
  auto t = std::make_shared<SceneTexture>();
  // Each file decoded once; -2: not yet tried.
  std::vector<int> image_of_file(attributes.files.size(), -2);
  t->face_image.assign(num_faces, -1);
  t->corner_uv.resize(6 * num_faces);
  for (std::size_t f = 0; f < num_faces; ++f) {
    const int file = f < file_of_face.size() ? file_of_face[f] : -1;
    if (file >= 0 && image_of_file[file] == -2) {
      const std::string& bytes = attributes.files[file].bytes();
      const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
      const int length = static_cast<int>(std::min<std::size_t>(bytes.size(), INT32_MAX));
      int w = 0, h = 0, channels = 0;
      // The size first: a small file may declare a huge image (20000 x 20000 took 3.1 GB before this check).
      const bool huge = stbi_info_from_memory(data, length, &w, &h, &channels) &&
                        static_cast<long long>(w) * h > kMaxTexturePixels;
      stbi_uc* pixels = huge ? nullptr : stbi_load_from_memory(data, length, &w, &h, &channels, 4);
      if (!pixels) {
        t->problems.push_back(attributes.files[file].name + ": " +
                              (huge ? std::to_string(w) + " x " + std::to_string(h) +
                                          " pixels, more than the viewer draws (" +
                                          std::to_string(kMaxTexturePixels) + ")"
                                    : std::string(stbi_failure_reason())));
        image_of_file[file] = -1;
      } else {
        TextureLevel level;
        level.width = w, level.height = h;
        level.rgba.resize(4 * static_cast<std::size_t>(w) * h);
        // The image's top row first in the file; OpenGL's first row is v = 0, the bottom.
        for (int y = 0; y < h; ++y)
          std::memcpy(&level.rgba[4 * static_cast<std::size_t>(w) * y],
                      pixels + 4 * static_cast<std::size_t>(w) * (h - 1 - y),
                      4 * static_cast<std::size_t>(w));
        stbi_image_free(pixels);
        TextureImage image;
        image.levels.push_back(std::move(level));
        while (image.levels.back().width > 1 || image.levels.back().height > 1)
          image.levels.push_back(half(image.levels.back()));
        image_of_file[file] = static_cast<int>(t->images.size());
        t->images.push_back(std::move(image));
      }
    }
    t->face_image[f] = file >= 0 ? image_of_file[file] : -1;
    for (int c = 0; c < 3; ++c) {
      const std::array<double, 2>& uv = attributes.texcoords.empty()
                                            ? attributes.corner_uv[attributes.corner_uv_index[f][c]]
                                            : attributes.texcoords[faces[f][c]];
      t->corner_uv[6 * f + 2 * c] = static_cast<float>(uv[0]);
      t->corner_uv[6 * f + 2 * c + 1] = static_cast<float>(uv[1]);
    }
  }
  return t;
}

}  // namespace strata::viewer
