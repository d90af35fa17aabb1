// Measured optical constants of metals (metals.hpp). The numbers are those the cited papers
// tabulate, wavelength converted from the papers' photon energies or micrometres to nm; see
// docs/theory/bibliography.md for each key.
#include "microsim/models/metals.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "microsim/common.hpp"

namespace microsim::models {

namespace {

// [JohnsonChristy72] gold, room temperature, 187.9 - 1937 nm (49 photon energies).
const OpticalConstant kGoldJohnsonChristy[] = {
    {187.9, 1.28, 1.188},
    {191.6, 1.32, 1.203},
    {195.3, 1.34, 1.226},
    {199.3, 1.33, 1.251},
    {203.3, 1.33, 1.277},
    {207.3, 1.30, 1.304},
    {211.9, 1.30, 1.350},
    {216.4, 1.30, 1.387},
    {221.4, 1.30, 1.427},
    {226.2, 1.31, 1.460},
    {231.3, 1.30, 1.497},
    {237.1, 1.32, 1.536},
    {242.6, 1.32, 1.577},
    {249.0, 1.33, 1.631},
    {255.1, 1.33, 1.688},
    {261.6, 1.35, 1.749},
    {268.9, 1.38, 1.803},
    {276.1, 1.43, 1.847},
    {284.4, 1.47, 1.869},
    {292.4, 1.49, 1.878},
    {300.9, 1.53, 1.889},
    {310.7, 1.53, 1.893},
    {320.4, 1.54, 1.898},
    {331.5, 1.48, 1.883},
    {342.5, 1.48, 1.871},
    {354.2, 1.50, 1.866},
    {367.9, 1.48, 1.895},
    {381.5, 1.46, 1.933},
    {397.4, 1.47, 1.952},
    {413.3, 1.46, 1.958},
    {430.5, 1.45, 1.948},
    {450.9, 1.38, 1.914},
    {471.4, 1.31, 1.849},
    {495.9, 1.04, 1.833},
    {520.9, 0.62, 2.081},
    {548.6, 0.43, 2.455},
    {582.1, 0.29, 2.863},
    {616.8, 0.21, 3.272},
    {659.5, 0.14, 3.697},
    {704.5, 0.13, 4.103},
    {756.0, 0.14, 4.542},
    {821.1, 0.16, 5.083},
    {892.0, 0.17, 5.663},
    {984.0, 0.22, 6.350},
    {1088.0, 0.27, 7.150},
    {1216.0, 0.35, 8.145},
    {1393.0, 0.43, 9.519},
    {1610.0, 0.56, 11.21},
    {1937.0, 0.92, 13.78},
};

// [JohnsonChristy72] silver, room temperature, 187.9 - 1937 nm.
const OpticalConstant kSilverJohnsonChristy[] = {
    {187.9, 1.07, 1.212},
    {191.6, 1.10, 1.232},
    {195.3, 1.12, 1.255},
    {199.3, 1.14, 1.277},
    {203.3, 1.15, 1.296},
    {207.3, 1.18, 1.312},
    {211.9, 1.20, 1.325},
    {216.4, 1.22, 1.336},
    {221.4, 1.25, 1.342},
    {226.2, 1.26, 1.344},
    {231.3, 1.28, 1.357},
    {237.1, 1.28, 1.367},
    {242.6, 1.30, 1.378},
    {249.0, 1.31, 1.389},
    {255.1, 1.33, 1.393},
    {261.6, 1.35, 1.387},
    {268.9, 1.38, 1.372},
    {276.1, 1.41, 1.331},
    {284.4, 1.41, 1.264},
    {292.4, 1.39, 1.161},
    {300.9, 1.34, 0.964},
    {310.7, 1.13, 0.616},
    {320.4, 0.81, 0.392},
    {331.5, 0.17, 0.829},
    {342.5, 0.14, 1.142},
    {354.2, 0.10, 1.419},
    {367.9, 0.07, 1.657},
    {381.5, 0.05, 1.864},
    {397.4, 0.05, 2.070},
    {413.3, 0.05, 2.275},
    {430.5, 0.04, 2.462},
    {450.9, 0.04, 2.657},
    {471.4, 0.05, 2.869},
    {495.9, 0.05, 3.093},
    {520.9, 0.05, 3.324},
    {548.6, 0.06, 3.586},
    {582.1, 0.05, 3.858},
    {616.8, 0.06, 4.152},
    {659.5, 0.05, 4.483},
    {704.5, 0.04, 4.838},
    {756.0, 0.03, 5.242},
    {821.1, 0.04, 5.727},
    {892.0, 0.04, 6.312},
    {984.0, 0.04, 6.992},
    {1088.0, 0.04, 7.795},
    {1216.0, 0.09, 8.828},
    {1393.0, 0.13, 10.10},
    {1610.0, 0.15, 11.85},
    {1937.0, 0.24, 14.08},
};

// [JohnsonChristy72] copper, room temperature, 187.9 - 1937 nm.
const OpticalConstant kCopperJohnsonChristy[] = {
    {187.9, 0.94, 1.337},
    {191.6, 0.95, 1.388},
    {195.3, 0.97, 1.440},
    {199.3, 0.98, 1.493},
    {203.3, 0.99, 1.550},
    {207.3, 1.01, 1.599},
    {211.9, 1.04, 1.651},
    {216.4, 1.08, 1.699},
    {221.4, 1.13, 1.737},
    {226.2, 1.18, 1.768},
    {231.3, 1.23, 1.792},
    {237.1, 1.28, 1.802},
    {242.6, 1.34, 1.799},
    {249.0, 1.37, 1.783},
    {255.1, 1.41, 1.741},
    {261.6, 1.41, 1.691},
    {268.9, 1.45, 1.668},
    {276.1, 1.46, 1.646},
    {284.4, 1.45, 1.633},
    {292.4, 1.42, 1.633},
    {300.9, 1.40, 1.679},
    {310.7, 1.38, 1.729},
    {320.4, 1.38, 1.783},
    {331.5, 1.34, 1.821},
    {342.5, 1.36, 1.864},
    {354.2, 1.37, 1.916},
    {367.9, 1.36, 1.975},
    {381.5, 1.33, 2.045},
    {397.4, 1.32, 2.116},
    {413.3, 1.28, 2.207},
    {430.5, 1.25, 2.305},
    {450.9, 1.24, 2.397},
    {471.4, 1.25, 2.483},
    {495.9, 1.22, 2.564},
    {520.9, 1.18, 2.608},
    {548.6, 1.02, 2.577},
    {582.1, 0.70, 2.704},
    {616.8, 0.30, 3.205},
    {659.5, 0.22, 3.747},
    {704.5, 0.21, 4.205},
    {756.0, 0.24, 4.665},
    {821.1, 0.26, 5.180},
    {892.0, 0.30, 5.768},
    {984.0, 0.32, 6.421},
    {1088.0, 0.36, 7.217},
    {1216.0, 0.48, 8.245},
    {1393.0, 0.60, 9.439},
    {1610.0, 0.76, 11.12},
    {1937.0, 1.09, 13.43},
};

// [McPeak15], aluminium: thermally evaporated film, template-stripped; every 5 nm, the rows
// from 345 to 855 nm (the paper's data run from 150 to 1700 nm).
const OpticalConstant kAluminiumMcPeak[] = {
    {345.0, 0.275201252, 3.607178361},
    {350.0, 0.28349792, 3.663518946},
    {355.0, 0.291774119, 3.719829584},
    {360.0, 0.300125667, 3.776251503},
    {365.0, 0.308578012, 3.831608068},
    {370.0, 0.317597538, 3.889198914},
    {375.0, 0.32692637, 3.945995546},
    {380.0, 0.335956002, 4.002607455},
    {385.0, 0.345714203, 4.058265431},
    {390.0, 0.354901676, 4.114238107},
    {395.0, 0.364968364, 4.169676475},
    {400.0, 0.375150842, 4.226433266},
    {405.0, 0.385211589, 4.281283449},
    {410.0, 0.396086448, 4.336805792},
    {415.0, 0.40706511, 4.391435073},
    {420.0, 0.417647849, 4.447407079},
    {425.0, 0.429543735, 4.503499508},
    {430.0, 0.440996226, 4.559109307},
    {435.0, 0.452837879, 4.613682059},
    {440.0, 0.464232752, 4.669101846},
    {445.0, 0.477070026, 4.724044433},
    {450.0, 0.489220122, 4.778319404},
    {455.0, 0.501228231, 4.832828338},
    {460.0, 0.514817248, 4.887948117},
    {465.0, 0.528042125, 4.943260916},
    {470.0, 0.53987657, 4.997345967},
    {475.0, 0.554932886, 5.051331558},
    {480.0, 0.568005038, 5.105940631},
    {485.0, 0.582771419, 5.159226931},
    {490.0, 0.596705366, 5.212874187},
    {495.0, 0.610784373, 5.265933683},
    {500.0, 0.625686295, 5.320477736},
    {505.0, 0.640306464, 5.374848125},
    {510.0, 0.655709839, 5.428163169},
    {515.0, 0.672565753, 5.481545831},
    {520.0, 0.688336416, 5.535955836},
    {525.0, 0.704045108, 5.58799423},
    {530.0, 0.720793584, 5.641767754},
    {535.0, 0.737603948, 5.693773756},
    {540.0, 0.75446839, 5.746496546},
    {545.0, 0.772330366, 5.799008035},
    {550.0, 0.789405353, 5.851936501},
    {555.0, 0.808351698, 5.905288517},
    {560.0, 0.829205097, 5.958236408},
    {565.0, 0.848630853, 6.009090973},
    {570.0, 0.867376853, 6.060226283},
    {575.0, 0.887661988, 6.112687118},
    {580.0, 0.908569739, 6.165184423},
    {585.0, 0.928308533, 6.215605902},
    {590.0, 0.948955518, 6.267417058},
    {595.0, 0.9714896, 6.317103137},
    {600.0, 0.992465612, 6.368986418},
    {605.0, 1.016073317, 6.417351867},
    {610.0, 1.038145667, 6.46681888},
    {615.0, 1.062059906, 6.517052343},
    {620.0, 1.088160063, 6.566589093},
    {625.0, 1.112663572, 6.61475776},
    {630.0, 1.136328574, 6.66312559},
    {635.0, 1.165731637, 6.710806975},
    {640.0, 1.190265203, 6.759417967},
    {645.0, 1.218505245, 6.807110623},
    {650.0, 1.246364405, 6.852329839},
    {655.0, 1.275302761, 6.898361917},
    {660.0, 1.304382818, 6.942363757},
    {665.0, 1.333854457, 6.987643931},
    {670.0, 1.365410391, 7.031951759},
    {675.0, 1.395892303, 7.071104251},
    {680.0, 1.426024482, 7.116287362},
    {685.0, 1.457391234, 7.157652493},
    {690.0, 1.493230683, 7.197481356},
    {695.0, 1.5274935, 7.23603734},
    {700.0, 1.559751729, 7.27391404},
    {705.0, 1.596346402, 7.311383032},
    {710.0, 1.631621525, 7.34575992},
    {715.0, 1.669698976, 7.380372258},
    {720.0, 1.706780893, 7.414249862},
    {725.0, 1.745260386, 7.446739811},
    {730.0, 1.786398844, 7.475374294},
    {735.0, 1.827772224, 7.502849546},
    {740.0, 1.872189153, 7.528352557},
    {745.0, 1.916802427, 7.55216072},
    {750.0, 1.958355454, 7.571403838},
    {755.0, 2.005349601, 7.585211073},
    {760.0, 2.054224115, 7.599462923},
    {765.0, 2.09984451, 7.605086914},
    {770.0, 2.144528834, 7.61216158},
    {775.0, 2.189915668, 7.610567038},
    {780.0, 2.231500036, 7.603853787},
    {785.0, 2.275479945, 7.589387919},
    {790.0, 2.314643646, 7.572223927},
    {795.0, 2.350258044, 7.547894599},
    {800.0, 2.373653298, 7.522581337},
    {805.0, 2.399438967, 7.486541749},
    {810.0, 2.409296598, 7.449477169},
    {815.0, 2.414395973, 7.410756231},
    {820.0, 2.410049326, 7.369351244},
    {825.0, 2.399462094, 7.325600203},
    {830.0, 2.375277499, 7.288411569},
    {835.0, 2.342102357, 7.253098886},
    {840.0, 2.301774531, 7.225729444},
    {845.0, 2.257656113, 7.204374444},
    {850.0, 2.204898553, 7.188085811},
    {855.0, 2.148111401, 7.177700369},
};

template <std::size_t N>
IndexTable table_of(const char* name, const char* source, const OpticalConstant (&rows)[N]) {
  return IndexTable{name, source, std::vector<OpticalConstant>(rows, rows + N)};
}

const std::vector<IndexTable>& metals() {
  static const std::vector<IndexTable> all = {
      table_of("Au", "JohnsonChristy72", kGoldJohnsonChristy),
      table_of("Ag", "JohnsonChristy72", kSilverJohnsonChristy),
      table_of("Cu", "JohnsonChristy72", kCopperJohnsonChristy),
      table_of("Al", "McPeak15", kAluminiumMcPeak),
  };
  return all;
}

std::string number_text(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

}  // namespace

OpticalConstant IndexTable::at(double nm) const {
  if (!(nm >= min_nm() && nm <= max_nm()))
    throw std::out_of_range("wavelength " + number_text(nm) + " nm outside the table of " + name);
  const auto hi = std::lower_bound(rows.begin(), rows.end(), nm,
                                   [](const OpticalConstant& r, double x) { return r.wavelength_nm < x; });
  if (hi->wavelength_nm == nm) return *hi;
  const OpticalConstant& b = *hi;
  const OpticalConstant& a = *(hi - 1);
  const double t = (nm - a.wavelength_nm) / (b.wavelength_nm - a.wavelength_nm);
  return {nm, a.n + t * (b.n - a.n), a.k + t * (b.k - a.k)};
}

const std::vector<std::string>& metal_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const IndexTable& t : metals()) v.push_back(t.name);
    return v;
  }();
  return names;
}

const IndexTable& metal_table(const std::string& symbol) {
  for (const IndexTable& t : metals())
    if (t.name == symbol) return t;
  std::string choices;
  for (const std::string& n : metal_names()) choices += (choices.empty() ? "" : ", ") + n;
  throw ParameterError("{metal} must be one of " + choices + " (got '" + literal_text(symbol) + "')");
}

namespace {

// The fields of one CSV line: separated by commas, spaces or tabs.
std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == ',' || c == ' ' || c == '\t' || c == '\r') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool parse_number(const std::string& s, double* x) {
  std::istringstream in(s);
  in >> *x;
  return !in.fail() && in.peek() == std::char_traits<char>::eof();
}

}  // namespace

IndexTable read_index_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ParameterError("{ior_file}: cannot read " + literal_text(path));
  IndexTable t{path, "file", {}};
  std::string line;
  int line_no = 0;
  bool header_allowed = true;
  auto fail = [&](const std::string& what) {
    throw ParameterError("{ior_file} " + literal_text(path) + ":" + std::to_string(line_no) + ": " + literal_text(what));
  };
  while (std::getline(in, line)) {
    ++line_no;
    const std::vector<std::string> f = split_fields(line);
    if (f.empty() || f[0][0] == '#') continue;
    double v[3];
    bool numeric = f.size() == 3;
    for (std::size_t c = 0; numeric && c < 3; ++c) numeric = parse_number(f[c], &v[c]);
    if (!numeric) {
      // One header line of names before the first row.
      double dummy;
      const bool names = std::none_of(f.begin(), f.end(), [&](const std::string& s) { return parse_number(s, &dummy); });
      if (header_allowed && names) {
        header_allowed = false;
        continue;
      }
      fail("expected three numbers 'wavelength_nm, n, k' (got '" + line + "')");
    }
    header_allowed = false;
    if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]))) fail("values must be finite");
    if (!(v[0] > 0)) fail("the wavelength must be positive (nm)");
    if (!(v[1] > 0)) fail("n must be > 0 (got " + f[1] + ")");
    if (!(v[2] >= 0)) fail("k must be >= 0 (got " + f[2] + ")");
    if (!t.rows.empty() && !(v[0] > t.rows.back().wavelength_nm))
      fail("wavelengths must increase (" + f[0] + " after " + number_text(t.rows.back().wavelength_nm) + ")");
    t.rows.push_back({v[0], v[1], v[2]});
  }
  if (t.rows.size() < 2) throw ParameterError("{ior_file} " + literal_text(path) + ": needs at least two rows 'wavelength_nm, n, k'");
  return t;
}

std::vector<double> default_wavelengths_nm() { return {450.0, 500.0, 550.0, 600.0, 650.0}; }

void check_wavelengths(const std::vector<double>& nm, const IndexTable& table, const std::string& option) {
  if (nm.empty()) throw ParameterError(option + " needs at least one wavelength");
  for (std::size_t i = 0; i < nm.size(); ++i) {
    if (!table.covers(nm[i]))
      throw ParameterError(option + ": " + number_text(nm[i]) + " nm is outside the index table of " + literal_text(table.name) +
                       " (" + number_text(table.min_nm()) + " - " + number_text(table.max_nm()) + " nm)");
    if (i > 0 && !(nm[i] > nm[i - 1])) throw ParameterError(option + " must be increasing wavelengths in nm");
  }
}

}  // namespace microsim::models
