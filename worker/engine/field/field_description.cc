#include "worker/engine/field/field_description.h"

#include <sstream>

namespace endorecon::field {
namespace {

template <typename S>
std::string Widths(const Mlp<S>& mlp) {
  std::string w = std::to_string(mlp.in_dim());
  for (int k = 0; k < mlp.hidden_layers(); ++k) w += " -> " + std::to_string(mlp.hidden_dim(k));
  return w + " -> " + std::to_string(mlp.out_dim());
}

}  // namespace

template <typename S>
std::string DescribeField(const FieldT<S>& field) {
  const FieldConfig& config = field.config();
  std::ostringstream s;
  if (const auto* frequency = field.frequency()) {
    s << "frequency encoding: " << frequency->frequencies() << " frequencies, " << frequency->output_dim()
      << " values (no hash grids, no temporal blend)\n";
  } else {
    const auto& grids = *field.grids();
    s << "hash grids: " << grids.grids() << " x (" << config.grids.features << " features/level, 2^"
      << config.grids.log2_table << " slots), blended feature width " << grids.feature_dim() << "\n";
    for (int k = 0; k < grids.grids(); ++k) {
      const auto& grid = grids.grid(k);
      s << "  grid " << k << ": base " << grid.config().base_resolution << ", scale " << grid.config().scale
        << ", " << grid.levels() << " levels (resolution " << grid.level(0).res << ".."
        << grid.level(grid.levels() - 1).res;
      int dense = 0;
      for (int l = 0; l < grid.levels(); ++l) dense += static_cast<int>(grid.level(l).dense);
      s << ", " << dense << " dense)";
      if (grid.dropped_levels() > 0) {
        s << "; left out " << grid.dropped_levels() << " finer levels (above resolution cap "
          << config.grids.max_resolution << ")";
      }
      s << "\n";
    }
    s << "temporal blend: 1 -> " << field.blend()->hidden_dim() << " -> " << field.blend()->grids()
      << " softmax\n";
  }
  if (field.deformation()) {
    s << "deformation: 4D grid " << config.deformation.resolution << "^3 cells x "
      << config.deformation.time_knots << " time knots\n";
  } else {
    s << "deformation: left out (static scene)\n";
  }
  if (field.exposure()) {
    s << "exposure: a gain per colour channel at " << field.exposure()->knots()
      << " knots (the training frames' times)\n";
  }
  if (field.background()) s << "background: learned per ray direction (spherical harmonics to band 3)\n";
  s << "density head: " << Widths(field.density().mlp()) << ", colour head: " << Widths(field.color().mlp());
  if (field.color().time_frequencies() > 0)
    s << " (" << field.color().time_frequencies() << " time frequencies in)";
  s << ", dropout " << config.heads.dropout;
  if (config.heads.ColorDropout() != config.heads.dropout)
    s << " (colour " << config.heads.ColorDropout() << ")";
  s << "\n";
  s << "parameters:";
  for (const auto& b : field.Blocks()) s << " " << b.name << " " << b.size;
  return s.str();
}

template std::string DescribeField(const FieldT<float>&);
template std::string DescribeField(const FieldT<double>&);

}  // namespace endorecon::field
