// Tabulated spectral curves (QE, transmissions) and the readers for the files they come in.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/physics.h"

namespace pyrocam {

// A numeric CSV table: optional '#' comment lines, one header row, numeric rows.
struct CsvTable {
  std::filesystem::path path;
  std::vector<std::string> header;
  std::vector<std::vector<double>> columns;  // columns[c][row]

  // Index of a named column; throws InputError naming the file and the available columns.
  std::size_t column_index(const std::string& name) const;
};

CsvTable read_csv_table(const std::filesystem::path& path);

// A curve sampled at strictly increasing wavelengths.
struct Spectrum {
  std::vector<double> wavelength_nm;
  std::vector<double> value;
  std::string origin;  // file (and column) it was read from, for messages

  // Linear interpolation onto the grid. Throws InputError if the curve does not cover the grid.
  Eigen::VectorXd resample(const WavelengthGrid& grid) const;
};

// Reads column `column` (by name; empty = the only value column) against `wavelength_nm`.
// Checks: strictly increasing wavelengths, finite values, values within [0, max_value].
Spectrum read_spectrum_csv(const std::filesystem::path& path, const std::string& column,
                           double max_value = 1.0);

// Per-band 1 nm responses of an IMEC snapshot-mosaic factory calibration (XML). Returns one
// spectrum per band in the file's band index order.
std::vector<Spectrum> read_imec_band_responses(const std::filesystem::path& path);

}  // namespace pyrocam
