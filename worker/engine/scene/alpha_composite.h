// Straight-alpha RGBA images onto an opaque background, as NeRF-synthetic captures are read (objects
// on transparency). Shared by the image reader (frame_reader.h) and captures made in memory
// (synthetic_object.h), so both give the same bytes. No OpenCV.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace endorecon::scene {

// rgb[3i + c] = round((rgba[4i + c] a + background[c] (255 - a)) / 255) with a = rgba[4i + 3], for
// `pixels` pixels (RGBA and RGB order); true when some pixel was not opaque.
bool CompositeRgbaOnto(const std::uint8_t* rgba, std::size_t pixels,
                       const std::array<std::uint8_t, 3>& background, std::uint8_t* rgb);

}  // namespace endorecon::scene
