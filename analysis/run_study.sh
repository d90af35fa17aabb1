#!/bin/sh
# Runs one long study at the sizes of its published record and writes its page:
#   analysis/run_study.sh NAME BUILD_DIR
# writes BUILD_DIR/studies/study_NAME.md (the page of docs/findings/records/, regenerated).
# NAME: convergence, converged_models, guard_band_bias, structured_surfaces, walk_audit, albedo_lut,
# spectral_polarized (also writes the figures of docs/findings/spectral-polarized.md to
# BUILD_DIR/studies/spectral_polarized/img).
# Hours for convergence and converged_models, tens of minutes for the others, on 2 cores.
set -eu
SRC=$(cd "$(dirname "$0")/.." && pwd)
NAME=$1
BUILD=$(cd "$2" && pwd)
OUT="$BUILD/studies"
mkdir -p "$OUT"
RAW="$OUT/$NAME.raw.md"
page() { /usr/bin/python3 "$SRC/analysis/study_page.py" "$1" "study_$NAME" < "$RAW" > "$OUT/study_$NAME.md"
         rm -f "$RAW"; echo "wrote $OUT/study_$NAME.md"; }
case "$NAME" in
  convergence)
    KINDS="gaussian:0.5 gaussian:1.0 gaussian:0.2 gaussian-ggx:0.5" \
      "$SRC/analysis/convergence.sh" "$BUILD" "$OUT/convergence" >&2
    cp "$OUT/convergence/convergence.md" "$RAW"
    page "Discretization study of Gaussian heightfields" ;;
  converged_models)
    : > "$RAW"
    for cells in 16 4; do
      CELLS_PER_L=$cells RAYS_G=500000 RAYS_T4=1048576 ALPHAS_T4="0.4 0.7 1.0 1.3" \
        "$SRC/analysis/converged_models.sh" "$BUILD" "$OUT/converged_models_c$cells" >&2
      /usr/bin/python3 "$SRC/analysis/converged_models.py" "$OUT/converged_models_c$cells" "$cells" >> "$RAW"
    done
    page "Model statements on converged tiles" ;;
  guard_band_bias)
    "$SRC/analysis/guard_band_bias.sh" "$BUILD" --resolution 512 --rays 300000 --bsdf-rays 300000 \
      --guards 0,1,2,4,8,12 > "$RAW"
    page "Guard band bias of heightfield windows" ;;
  structured_surfaces)
    "$SRC/analysis/tables_structured_surfaces.sh" "$BUILD" > "$RAW"
    page "Structured and non-heightfield microsurfaces" ;;
  walk_audit)
    OUT_FILE="$RAW" "$SRC/analysis/walk_audit.sh" "$BUILD" >&2
    page "Mirror walk audit of orders 4 and above" ;;
  albedo_lut)
    "$SRC/analysis/albedo_lut.sh" "$BUILD" "$OUT/albedo_lut" > "$RAW"
    page "Albedo lookup tables of mirror heightfields" ;;
  spectral_polarized)
    /usr/bin/python3 "$SRC/analysis/spectral_polarized.py" --build "$BUILD" --out "$OUT/spectral_polarized" \
      --check >&2
    cp "$OUT/spectral_polarized/spectral_polarized.md" "$RAW"
    page "Spectral and polarized multiple scattering" ;;
  *) echo "unknown study: $NAME" >&2; exit 2 ;;
esac
