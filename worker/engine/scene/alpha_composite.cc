#include "worker/engine/scene/alpha_composite.h"

namespace endorecon::scene {

bool CompositeRgbaOnto(const std::uint8_t* rgba, std::size_t pixels,
                       const std::array<std::uint8_t, 3>& background, std::uint8_t* rgb) {
  bool transparent = false;
  for (std::size_t i = 0; i < pixels; ++i, rgba += 4, rgb += 3) {
    const int a = rgba[3];
    transparent = transparent || a < 255;
    for (int c = 0; c < 3; ++c)
      rgb[c] = static_cast<std::uint8_t>((rgba[c] * a + background[c] * (255 - a) + 127) / 255);
  }
  return transparent;
}

}  // namespace endorecon::scene
