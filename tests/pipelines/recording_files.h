// Reading back what the recording tests make: CSV, .npy files, a shell command's status,
// and the stream tags of a Matroska segment (shared by test_recordings*.cpp).
#pragma once

#include <gst/gst.h>
#include <gst/pbutils/pbutils.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "test_support.h"

namespace pyrocam::test::recording_files {

namespace fs = std::filesystem;

inline std::vector<std::vector<std::string>> read_csv(const fs::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(read_text(path));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
      cells.push_back(line.substr(start, comma - start));
    cells.push_back(line.substr(start));
    rows.push_back(cells);
  }
  return rows;
}

// A shell command's exit status, its output in `log`.
inline int run_command(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " > '" + log.string() + "' 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A .npy file: its dtype, shape and data bytes.
struct Npy {
  std::string descr;
  std::vector<long> shape;
  std::string data;
};
inline Npy read_npy(const fs::path& path) {
  const std::string bytes = read_text(path);
  Npy n;
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) return n;
  const std::size_t len = static_cast<unsigned char>(bytes[8]) |
                          static_cast<std::size_t>(static_cast<unsigned char>(bytes[9])) << 8;
  const std::string header = bytes.substr(10, len);
  const std::size_t d = header.find("'descr': '");
  if (d != std::string::npos) n.descr = header.substr(d + 10, header.find('\'', d + 10) - d - 10);
  const std::size_t s = header.find("'shape': (");
  if (s != std::string::npos) {
    std::istringstream shape(header.substr(s + 10, header.find(')', s) - s - 10));
    for (std::string part; std::getline(shape, part, ',');)
      if (part.find_first_not_of(' ') != std::string::npos) n.shape.push_back(std::stol(part));
  }
  n.data = bytes.substr(10 + len);
  return n;
}

// The stream tags GstDiscoverer finds in a file, as title and comment.
inline std::pair<std::string, std::string> discovered_tags(const std::string& path) {
  GError* error = nullptr;
  GstDiscoverer* discoverer = gst_discoverer_new(10 * GST_SECOND, &error);
  g_clear_error(&error);
  if (!discoverer) return {};
  gchar* uri = gst_filename_to_uri(path.c_str(), nullptr);
  GstDiscovererInfo* info = gst_discoverer_discover_uri(discoverer, uri, &error);
  g_free(uri);
  g_clear_error(&error);
  std::pair<std::string, std::string> out;
  if (info) {
    GList* streams = gst_discoverer_info_get_video_streams(info);
    const GstTagList* tags =
        streams ? gst_discoverer_stream_info_get_tags(GST_DISCOVERER_STREAM_INFO(streams->data))
                : nullptr;
    gchar* v = nullptr;
    if (tags && gst_tag_list_get_string(tags, GST_TAG_TITLE, &v)) out.first = v;
    g_free(v);
    v = nullptr;
    if (tags && gst_tag_list_get_string(tags, GST_TAG_COMMENT, &v)) out.second = v;
    g_free(v);
    gst_discoverer_stream_info_list_free(streams);
    g_object_unref(info);
  }
  g_object_unref(discoverer);
  return out;
}

}  // namespace pyrocam::test::recording_files
