// Recordings made by pipelines/record.sh (a folder of FFV1/Matroska segments of GRAY16_LE
// temperature codes, temperature-NNNNN.mkv) decoded frame by frame with GStreamer, and the
// description ratiotemp tags them with.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace pyrocam::cli {

// The segments of a recording folder, in order (a segment file is taken as a recording of one).
// Throws InputError naming the folder when it does not exist or holds none.
std::vector<std::filesystem::path> recording_segments(const std::filesystem::path& where,
                                                      const std::string& prefix = "temperature-");

struct RecordingDescription;

struct RecordingFrame {
  const RecordingDescription* tags = nullptr;  // what the segment's tags said so far
  std::size_t index = 0;
  double timestamp_s = 0;  // from the start of the recording (segments follow one another)
  cv::Mat codes;           // CV_16U (GRAY16_LE) or CV_8U (GRAY8), owned by the frame
};

// What the segments' tags say: the comment's "key=value" fields (empty without pyrocam's tags).
struct RecordingDescription {
  std::string title, comment;
  std::map<std::string, std::string> fields;
  int width = 0, height = 0;  // of the frames
};

// Decodes every frame of the segments in order and hands it to `on_frame`. Throws InputError
// naming the file for one that is missing, not a Matroska FFV1 GRAY16/GRAY8 stream, corrupt or
// truncated before its first frame, or whose frame size differs from the first segment's.
RecordingDescription read_recording(const std::vector<std::filesystem::path>& segments,
                                    const std::function<void(const RecordingFrame&)>& on_frame);

}  // namespace pyrocam::cli
