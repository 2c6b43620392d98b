#!/bin/sh
# Renders the README's gallery (docs/gallery/*.png) from the models in ../shared/scenes/
# (see its SOURCES.md): smooth against faceted, a textured model, a glTF model, depth of
# field. Rerun it after a change that alters how things look:
#
#   sh scripts/gallery.sh [SCENES_DIR] [OUT_DIR]
#
# CLTRACE names the binary (default target/release/cltrace); CLTRACE_DEVICE picks the
# device as for any render; SPP the samples per pixel (default 256). Each image is
# 360x240, a few tens of KB.
set -eu
here="$(cd "$(dirname "$0")/.." && pwd)"
scenes="${1:-$here/../shared/scenes}"
out="${2:-$here/docs/gallery}"
bin="${CLTRACE:-$here/target/release/cltrace}"
spp="${SPP:-256}"
mkdir -p "$out"
# Path tracing unless the arguments pick another mode.
render() { "$bin" render --width 360 --height 240 --spp "$spp" "$@"; }
path="--shade path"

# The Utah teapot has no normals: computed ones with the default crease angle (60 degrees),
# then none at all, lit by a low sun so that the facets show.
sun="--shade shadow --light sun:1,1.5,0.8"
render "$scenes/utah_teapot.obj" $sun -o "$out/teapot-smooth.png"
render "$scenes/utah_teapot.obj" $sun --crease-angle 0 -o "$out/teapot-faceted.png"
# Spot: normals, texture coordinates and a base colour texture from its OBJ and MTL files.
front="--eye -1.7,1.1,-2.3 --look-at 0,0.25,0 --fov 40"
render "$scenes/spot.obj.gz" $path $front -o "$out/spot-textured.png"
# Suzanne: glTF 2.0 with its base colour texture and node transforms, the auto view.
render "$scenes/suzanne_gltf/Suzanne.gltf" $path -o "$out/suzanne-gltf.png"
# Depth of field: a lens 0.2 wide focused on Spot's face; the body behind it blurs.
render "$scenes/spot.obj.gz" $path $front --aperture 0.2 --focus-on -0.35,0.3,-0.5 \
    -o "$out/spot-depth-of-field.png"
ls -l "$out"
