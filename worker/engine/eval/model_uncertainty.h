// A second uncertainty map, of where the model itself is wrong apart from the camera's noise (the
// "model" map, uncertainty/NNNNNN_model.npy). The paper's map (the ray score of the aleatoric and
// epistemic variances) ranks the error against the observed image; with camera noise in the images
// its aleatoric part learns mostly that noise, which is stronger where the tissue is brighter (shot
// noise), so it ranks brightness as much as the model's error (docs/benchmarks.md, "Calibration on
// noisy images"). The model map divides each pixel's aleatoric score by the frame's median at the
// pixel's rendered brightness (the noise the camera adds there, as the model learned it), leaving
// the excess, and adds the epistemic score; both terms are taken relative to their mean over the
// frame's tissue, so neither swamps the other. Where the clip's frames are known (the evaluation of a
// clip, not `render` of new cameras), the neighbouring training frames add a third and a fourth term:
// their residuals, and the render's disagreement with their images (neighbour_evidence.h). It is for ranking
// pixels within a frame; its values are not variances.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace endorecon::eval {

// Brightness bins of the noise curve: the mean of R, G and B in [0, 1] split into this many.
inline constexpr int kNoiseCurveBins = 20;

// The model map of one frame (or of a grid of its pixels): rgb (3 per pixel, the rendered colour),
// the aleatoric and epistemic ray scores (one per pixel), tool_mask empty or one per pixel (1 = tool,
// left out of the medians and means; the map there is computed all the same). A bin with no tissue
// pixel takes the nearest bin's median. Throws InvalidArgument when the lengths disagree.
std::vector<float> ModelUncertainty(std::span<const float> rgb, std::span<const float> aleatoric,
                                    std::span<const float> epistemic,
                                    std::span<const std::uint8_t> tool_mask);

// The weights of the neighbouring frames' terms in the model map, relative to the aleatoric excess and
// the epistemic terms: their residuals (chosen on two clips, docs/benchmarks.md "The neighbours'
// residuals, averaged with their signs": 0.4-0.6 ranked best on the demo clip, 0.2-0.3 on the
// real-texture one) and the render's disagreement with their images ("The render against its
// neighbours' images": 0.4-0.6 best on the demo clip, neutral held out on the real-texture clips).
inline constexpr double kNeighbourEvidenceWeight = 0.4;
inline constexpr double kNeighbourDisagreementWeight = 0.4;

// Adds a neighbouring frames' term (neighbour_evidence.h; one value per pixel of the map) to a model
// map: weight times the term relative to its mean over the tissue (tool_mask as ModelUncertainty's). A
// term that is 0 everywhere adds nothing. Throws InvalidArgument when the lengths disagree.
void AddNeighbourTerm(std::span<float> map, std::span<const float> term, double weight,
                      std::span<const std::uint8_t> tool_mask);

// Each value divided by the median over the tissue of the values at pixels of the same rendered
// brightness (the mean of R, G and B in kNoiseCurveBins bins; a bin with no tissue pixel takes the
// nearest bin's median): what is left when the camera noise's level at that brightness is taken out.
// A median of 0 gives 0. rgb holds 3 values per pixel, values and tool_mask (or empty) one.
std::vector<float> RelativeToBrightnessMedian(std::span<const float> rgb, std::span<const float> values,
                                              std::span<const std::uint8_t> tool_mask);

}  // namespace endorecon::eval
