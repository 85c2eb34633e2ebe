#!/usr/bin/env bash
# Re-creates assets/scenes/ from the shared real data (see assets/README.md for provenance).
# The scenes are byte-for-byte copies: the SIYI ZR10 photos are 2560x1440 (3.7 MP), already a few
# megapixels and larger than the frames we render, so no resampling is needed and none is done.
# Usage: scripts/make_assets.sh [DATA_DIR]   (default: ../shared/data relative to the repo root)
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
data="${1:-$repo/../shared/data}"
mkdir -p "$repo/assets/scenes"
cp "$data/images/siyi_zr10/IMG_0100.jpg" "$repo/assets/scenes/siyi_zr10_img0100.jpg"
cp "$data/images/siyi_zr10/IMG_0150.jpg" "$repo/assets/scenes/siyi_zr10_img0150.jpg"
# Verify: the copies must match the recorded digests.
(cd "$repo/assets/scenes" && sha256sum -c <<'SUMS'
c7658507b54bfc0444445a438cfcece7657d59da48115a0d3fbbbcfa936f5d55  siyi_zr10_img0100.jpg
816783e176d79811905da53062b17ac3cbd20aa9a16ca4e172278a80b289d98d  siyi_zr10_img0150.jpg
SUMS
)
