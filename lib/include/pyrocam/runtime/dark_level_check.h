// Whether the dark subtracted from a camera's frames was the camera's own: a cold background
// reads 0 after the dark, within its noise, in every place of the mosaic alike. A dark level set
// too low leaves it reading the difference in every band (and adds that to the glowing object's
// bands, which then read a temperature that looks right and is wrong: a 1500 degC plate read
// 1534 degC with the dark 20 DN too low); one too high leaves it below 0.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pyrocam {

// Samples of a CV_32F dark-subtracted mosaic per place of its period (period_width x
// period_height: 2x2 Bayer, 5x5 snapshot), gathered over frames: each frame adds about 8192
// samples from every few rows of periods (a row further on in each frame, `frame`) and columns
// of periods, finite samples only (+INF marks saturation, NaN no reading).
struct DarkLevelSamples {
  int period_width = 0, period_height = 0;
  std::vector<std::vector<float>> by_place;  // [row * period_width + column]
};
void add_dark_level_samples(const cv::Mat& signal, int period_width, int period_height,
                            unsigned frame, DarkLevelSamples& samples);

// The verdict once every place has `min_samples`: per place, the centre of its darkest samples
// (from the means of its lowest 20 % and 5 %, as of a normal distribution: the mean of a cold
// background covering at least a fifth of the frame, whatever its noise). `offset_dn` is their mean
// when they all lie beyond the larger of 2 % of the full scale and 4 noise standard deviations on
// the same side of 0, within a factor of 1.2 of each other (a glowing body's bands differ by 1.44
// and more on the shipped cameras, dim or bright, and no body reads below 0); else 0.
struct DarkLevelVerdict {
  bool decided = false;  // enough samples
  double offset_dn = 0;  // > 0: the dark subtracted is about this much too low; < 0: too high
  double least_dn = 0, most_dn = 0;  // the places' centres
};
DarkLevelVerdict dark_level_verdict(DarkLevelSamples& samples, int bit_depth,
                                    std::size_t min_samples = 1024);

// The check over a stream of frames, as darksub and FrameMeasurer run it: every frame sampled
// until a first verdict, then every 8th (about 0.12 ms of CPU a 2048x2048 frame it samples).
class DarkLevelWatch {
 public:
  // A verdict when this frame brought one.
  std::optional<DarkLevelVerdict> add(const cv::Mat& signal, int period, int bit_depth);

 private:
  DarkLevelSamples samples_;
  unsigned frame_ = 0;
  bool decided_ = false;
};

// What a verdict with an offset says: "after the dark (<dark_used>) <frames> darkest parts read
// +20 DN ... the dark is about 20 DN too low for this camera, ...", `frames` e.g. "the frame's".
std::string dark_level_message(const DarkLevelVerdict& verdict, const std::string& dark_used,
                               const std::string& frames);

}  // namespace pyrocam
