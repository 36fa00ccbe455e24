#include "texture.h"

#include <stb_image.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "strata/mesh_io.h"

namespace strata::viewer {

bool has_texture(const MeshAttributes& attributes) {
  return (!attributes.texcoords.empty() || !attributes.corner_uv_index.empty()) &&
         !face_texture_files(attributes).empty();
}

std::shared_ptr<const SceneTexture> make_scene_texture(const MeshAttributes& attributes,
                                                       const std::vector<Face>& faces) {
  const std::size_t num_faces = faces.size();
  if (!has_texture(attributes)) return nullptr;
  const std::vector<int> file_of_face = face_texture_files(attributes);
  auto t = std::make_shared<SceneTexture>();
  // Each file decoded once; -2: not yet tried.
  std::vector<int> image_of_file(attributes.files.size(), -2);
  t->face_image.assign(num_faces, -1);
  t->corner_uv.resize(6 * num_faces);
  for (std::size_t f = 0; f < num_faces; ++f) {
    const int file = f < file_of_face.size() ? file_of_face[f] : -1;
    if (file >= 0 && image_of_file[file] == -2) {
      const std::string& bytes = attributes.files[file].bytes();
      int w = 0, h = 0, channels = 0;
      stbi_uc* pixels = stbi_load_from_memory(
          reinterpret_cast<const stbi_uc*>(bytes.data()),
          static_cast<int>(std::min<std::size_t>(bytes.size(), INT32_MAX)), &w, &h, &channels, 4);
      if (!pixels) {
        t->problems.push_back(attributes.files[file].name + ": " + stbi_failure_reason());
        image_of_file[file] = -1;
      } else {
        TextureImage image;
        image.width = w, image.height = h;
        image.rgba.resize(4 * static_cast<std::size_t>(w) * h);
        // The image's top row first in the file; OpenGL's first row is v = 0, the bottom.
        for (int y = 0; y < h; ++y)
          std::memcpy(&image.rgba[4 * static_cast<std::size_t>(w) * y],
                      pixels + 4 * static_cast<std::size_t>(w) * (h - 1 - y),
                      4 * static_cast<std::size_t>(w));
        stbi_image_free(pixels);
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
