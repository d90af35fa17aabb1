// Sphere previews of a measured RGL table beside the analytic single-scattering BRDF and the
// Smith random walk of the same NDF and material (sphere_preview.hpp), under a directional light
// and a uniform white environment, with the difference image: what `microsim render` computes
// and writes.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/render/sphere_preview.hpp"

namespace microsim::render {

// The models' parameters default to the table's (its description, as measure bsdf writes it):
// 0 or "" = from the table.
struct TablePreviewOptions {
  std::string table;  // an RGL .bsdf file
  PreviewOptions preview;
  double light_theta = 45.0, light_phi = 135.0;  // degrees, camera frame
  std::string distribution, material, against = "walk";
  double alpha = 0, alpha_x = 0, alpha_y = 0, eta = 0, k = 0;
  double white = 1.0, range = 0.1;  // PNG: radiance shown as white, difference shown as full colour
};

struct TablePreviews {
  // [directional, environment][measured, single, walk, difference]
  std::vector<PreviewImage> images[2];
  Json parameters, summary;  // the record's fields (summary: mean, rms, max_abs, mean_stderr per image)
  std::string table_description, layout;
  std::string distribution, material;
  double alpha_x = 0, alpha_y = 0, seconds = 0;
};

// Reads the table, resolves the models and renders the six images; UsageError (naming the
// option) for a file that is not a .bsdf table, angles out of range or models the table's
// description does not give and the options do not name.
TablePreviews render_table_previews(const TablePreviewOptions& o, const std::function<void(double)>& progress = {});
// EXR: every image and its standard error as channels LIGHT.COLUMN[_stderr], with the layout,
// parameters and summary as attributes.
void write_previews_exr(const std::string& path, const TablePreviews& p);
// PNG panel: rows directional, environment; columns measured, single, walk, difference.
void write_previews_png(const std::string& path, const TablePreviews& p, double white, double range);

}  // namespace microsim::render
