#!/usr/bin/env bash
# Builds the web viewer bundle that om.export(scene, "scene.html") inlines into every page:
# three.js (npm, MIT) + GLTFLoader + OrbitControls + viewer.js, minified by esbuild.  The versions are
# pinned by package.json and package-lock.json; the output is committed as package data, so users of
# omnirender need no Node.  Run it after changing viewer.js or the pinned versions:  tools/web-viewer/build.sh
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund --ignore-scripts
out=../../omnirender/formats/assets
mkdir -p "$out"
npx --no-install esbuild viewer.js --bundle --minify --format=iife --global-name=OmniRenderViewer \
  --target=es2020 --legal-comments=inline --log-level=warning --outfile="$out/three_viewer.min.js"
cp node_modules/three/LICENSE "$out/three.LICENSE"
version=$(node -p 'JSON.parse(require("fs").readFileSync("node_modules/three/package.json")).version')
echo "built $out/three_viewer.min.js (three.js $version, $(wc -c < "$out/three_viewer.min.js") bytes)"
