// Spectral complex indices of refraction n(lambda) + i k(lambda) of conductors: tables of measured
// optical constants shipped in the library (metals.cpp, each with its published source) and tables
// read from a CSV file (columns: wavelength in nm, n, k). Between tabulated wavelengths n and k are
// interpolated linearly in the wavelength, each on its own; outside the table there is no value.
#pragma once
#include <string>
#include <vector>

namespace microsim::models {

struct OpticalConstant {
  double wavelength_nm = 0.0;  // vacuum wavelength
  double n = 1.0;              // real part of the index
  double k = 0.0;              // extinction coefficient
};

struct IndexTable {
  std::string name;    // metal symbol, or the file's path
  std::string source;  // bibliography key and data set (docs/theory/bibliography.md), or "file"
  std::vector<OpticalConstant> rows;  // increasing wavelength, at least two rows

  double min_nm() const { return rows.front().wavelength_nm; }
  double max_nm() const { return rows.back().wavelength_nm; }
  bool covers(double nm) const { return nm >= min_nm() && nm <= max_nm(); }
  // n and k at `nm` (linear in the wavelength between the bracketing rows; a tabulated
  // wavelength returns its row exactly). std::out_of_range outside [min_nm, max_nm].
  OpticalConstant at(double nm) const;
};

// The shipped metals: "Au", "Ag", "Cu" [JohnsonChristy72] and "Al" [McPeak15].
const std::vector<std::string>& metal_names();
// The table of a shipped metal (case-sensitive symbol); UsageError naming the choices otherwise.
const IndexTable& metal_table(const std::string& symbol);

// Reads a CSV file of rows "wavelength_nm, n, k" (commas, spaces or tabs between the columns;
// blank lines and lines starting with '#' skipped; one header line of non-numbers allowed before
// the first row). Checked: three finite numbers per row, increasing wavelength, n > 0, k >= 0, at
// least two rows. UsageError "FILE:LINE: ..." otherwise (the command line's exit code 2).
IndexTable read_index_file(const std::string& path);

// The wavelengths of a spectral run when none are given: 450, 500, 550, 600 and 650 nm (the
// middle of the visible range, where the colour-matching functions are largest).
std::vector<double> default_wavelengths_nm();

// Checks a wavelength list against a table: at least one, each finite and inside the table's
// range, strictly increasing. ParameterError naming `option` (a "{parameter}" placeholder) and the table.
void check_wavelengths(const std::vector<double>& nm, const IndexTable& table, const std::string& option);

}  // namespace microsim::models
