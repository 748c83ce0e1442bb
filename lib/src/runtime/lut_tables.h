// The lookup table's file (lut_estimator.cpp): the table cache ratiotemp keeps between runs and
// the prebuilt table shipped beside a model (prebuilt_tables.h) share it (not installed).
//
// The file: kTableFileMagic; a header line of the table's fields (the model's fingerprint, the
// output space, the grid: blocks across and down, cell size and origin), the block count and
// the verdict ("-" for none); per block its index (uint32) and its floats (host byte order);
// then the checksum of everything before it (table_checksum) as a text line. A lookup table's
// block is kept as the network's answer at its 17 x 17 nodes, row after row.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pyrocam::lut {

// Bump when a block's values would change (grid rule, network arithmetic, output space).
// (3: the header ends with the tables' verdict; 4: blocks as their nodes, not their cells'
// corners: 3.5 times smaller.)
inline constexpr const char* kTableFileMagic = "pyrocam lookup-table cache 4\n";
// Cells along each side of a block: a header's cell size h times this is the block's size.
inline constexpr int kBlockCells = 16;

// FNV-1a over 8-byte words (then the tail's bytes), as 16 hex digits: eight times faster than
// bytewise FNV-1a over a file's megabytes.
std::string table_checksum(const char* data, std::size_t n);

// A table file read and checked (read_table_file): its bytes, its verdict and its blocks.
struct TableFile {
  std::string data;
  std::string verdict;  // "" for none
  std::size_t count = 0, header_bytes = 0, block_bytes = 0;
  std::uint32_t index(std::size_t k) const;
  const char* values(std::size_t k) const;  // block_bytes of floats
};

// The fields of a table file's header, read from its first line alone (the checksum is not
// checked: read_table_file does that); false when the file is not a table file of this version.
struct TableFields {
  std::string fingerprint;
  int space = 0, across = 0, down = 0;
  double h = 0, x0 = 0, y0 = 0;
};
bool read_table_fields(const std::string& path, TableFields& fields);

// Writes `blocks` (their `indices`, block_bytes each) atomically: a temporary file, then a
// rename. Throws InputError when it cannot.
void write_table_file(const std::string& path, const std::string& fields,
                      const std::string& verdict, const std::vector<std::uint32_t>& indices,
                      const std::vector<const float*>& blocks, std::size_t block_bytes);

// Throws InputError naming the file when it cannot be read, is not a table file of this version,
// was made for other fields (another model, grid or version), holds more than max_blocks, is
// truncated or altered (checksum), or names a block index of `slots` or more.
TableFile read_table_file(const std::string& path, const std::string& fields,
                          std::size_t block_bytes, std::size_t max_blocks, std::size_t slots);

}  // namespace pyrocam::lut
