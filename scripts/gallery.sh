#!/bin/sh
# Renders the README's gallery (docs/gallery/*.png) from the models in ../shared/scenes/
# (see its SOURCES.md): smooth against faceted, a textured model, a glTF model, depth of
# field, the scattering models, and a sun and sky. Rerun it after a change that alters how
# things look:
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
# Glass, gold, plastic, a mirror and a pane: scenes/materials.toml, cropped to 3:2. Light
# through glass and off mirrors (caustics) is found only by paths that happen to hit the
# light: these take 8 times the samples (and their PNGs shrink as the noise goes).
many=$((spp * 8))
render_many() { "$bin" render --width 360 --height 240 --spp "$many" "$@"; }
render_many "$here/scenes/materials.toml" -o "$out/materials.png"
# Lit by a sun and sky alone: a gold dragon (the sun's direction given), and a plastic
# bunny on a June evening in Munich (the sun's place in the sky from place and time).
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/dragon.toml" <<END
[[mesh]]
file = "$scenes/stanford_dragon.obj.gz"
material = { bsdf = "conductor", metal = "gold", roughness = 0.25 }
[ground]
albedo = [0.45, 0.45, 0.45]
[sky]
sun_direction = [-0.6, 0.55, 0.6]
turbidity = 3.0
intensity = 0.6
[render]
max_bounces = 8
END
render_many "$tmp/dragon.toml" $path -o "$out/dragon-sun-and-sky.png"
cat > "$tmp/bunny.toml" <<END
[[mesh]]
file = "$scenes/stanford_bunny.obj"
material = { bsdf = "plastic", albedo = [0.75, 0.72, 0.68], roughness = 0.3 }
[ground]
albedo = [0.45, 0.45, 0.45]
[sky]
latitude = 48.14
longitude = 11.58
time = "2026-06-21T19:45:00+02:00"
turbidity = 4.0
[render]
max_bounces = 8
END
render_many "$tmp/bunny.toml" $path -o "$out/bunny-evening-sky.png"
ls -l "$out"
