#include "runtime/lut_tables.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "pyrocam/core/error.h"

namespace pyrocam::lut {
namespace {

std::string header_line(const std::string& fields, std::size_t count, const std::string& verdict) {
  return std::string(kTableFileMagic) + fields + " " + std::to_string(count) + " " +
         (verdict.empty() ? "-" : verdict) + "\n";
}

}  // namespace

std::string table_checksum(const char* data, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, data + i, 8);
    h = (h ^ word) * 1099511628211ull;
  }
  for (; i < n; ++i) h = (h ^ static_cast<unsigned char>(data[i])) * 1099511628211ull;
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

std::uint32_t TableFile::index(std::size_t k) const {
  std::uint32_t i = 0;
  std::memcpy(&i, data.data() + header_bytes + k * (sizeof i + block_bytes), sizeof i);
  return i;
}

const char* TableFile::values(std::size_t k) const {
  return data.data() + header_bytes + k * (sizeof(std::uint32_t) + block_bytes) +
         sizeof(std::uint32_t);
}

void write_table_file(const std::string& path, const std::string& fields,
                      const std::string& verdict, const std::vector<std::uint32_t>& indices,
                      const std::vector<const float*>& blocks, std::size_t block_bytes) {
  std::string data = header_line(fields, indices.size(), verdict);
  data.reserve(data.size() + indices.size() * (sizeof(std::uint32_t) + block_bytes) + 17);
  for (std::size_t k = 0; k < indices.size(); ++k) {
    data.append(reinterpret_cast<const char*>(&indices[k]), sizeof(std::uint32_t));
    data.append(reinterpret_cast<const char*>(blocks[k]), block_bytes);
  }
  data += table_checksum(data.data(), data.size()) + "\n";
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    out.close();
    if (!out) {
      std::remove(temporary.c_str());
      throw InputError("could not write the lookup-table file " + temporary);
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw InputError("could not rename the lookup-table file to " + path);
  }
}

bool read_table_fields(const std::string& path, TableFields& f) {
  std::ifstream in(path, std::ios::binary);
  char head[512] = {};
  in.read(head, sizeof head - 1);
  const std::string text(head, static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  const std::size_t magic = std::strlen(kTableFileMagic);
  const std::size_t end = text.find('\n', magic);
  if (text.compare(0, magic, kTableFileMagic) != 0 || end == std::string::npos) return false;
  char fingerprint[64] = "";
  if (std::sscanf(text.substr(magic, end - magic).c_str(), "%63s %d %d %d %lg %lg %lg", fingerprint,
                  &f.space, &f.across, &f.down, &f.h, &f.x0, &f.y0) != 7)
    return false;
  f.fingerprint = fingerprint;
  return true;
}

TableFile read_table_file(const std::string& path, const std::string& fields,
                          std::size_t block_bytes, std::size_t max_blocks, std::size_t slots) {
  TableFile f;
  f.block_bytes = block_bytes;
  // A directory opens as a stream on Linux, whose size then read as an absurd one.
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw InputError("the lookup-table file " + path + " is not a regular file");
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError("cannot read the lookup-table file " + path);
  // No larger than the most blocks it may hold with a generous header: refused before it is read.
  const auto size = static_cast<std::size_t>(std::max<std::streamoff>(in.tellg(), 0));
  if (size > 4096 + max_blocks * (sizeof(std::uint32_t) + block_bytes) + 17)
    throw InputError("the lookup-table file " + path + " is larger than any table file");
  f.data.assign(size, '\0');
  in.seekg(0);
  in.read(f.data.data(), static_cast<std::streamsize>(f.data.size()));
  if (!in) throw InputError("cannot read the lookup-table file " + path);
  const std::string& data = f.data;
  const std::size_t magic = std::strlen(kTableFileMagic);
  const std::size_t header_end = data.find('\n', magic);
  if (data.compare(0, magic, kTableFileMagic) != 0 || header_end == std::string::npos)
    throw InputError("the file " + path + " is not a lookup-table file of this version");
  const std::string header = data.substr(0, header_end + 1);
  char verdict[64] = "";
  const std::size_t at = magic + fields.size();
  if (header.compare(magic, fields.size(), fields) != 0 ||
      std::sscanf(header.c_str() + at, " %zu %63s", &f.count, verdict) != 2 ||
      header != header_line(fields, f.count, verdict == std::string("-") ? "" : verdict))
    throw InputError("the lookup-table file " + path +
                     " is for another model, grid or version (header " +
                     header.substr(magic, header.size() - magic - 1) + ")");
  f.verdict = verdict == std::string("-") ? "" : verdict;
  f.header_bytes = header.size();
  const std::size_t body_end = f.header_bytes + f.count * (sizeof(std::uint32_t) + block_bytes);
  if (f.count > max_blocks || data.size() != body_end + 17 ||
      data.compare(body_end, 17, table_checksum(data.data(), body_end) + "\n") != 0)
    throw InputError("the lookup-table file " + path + " is truncated or altered (checksum)");
  for (std::size_t k = 0; k < f.count; ++k)
    if (f.index(k) >= slots)
      throw InputError("the lookup-table file " + path + " names a block outside the table");
  return f;
}

}  // namespace pyrocam::lut
