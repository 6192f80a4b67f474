#!/usr/bin/env bash
# Rebuild flexshaft/views/viewer/vendor/three-fs3.min.js: the parts of three.js the mode viewer uses, as one
# script that sets window.FS3 (no module loader, no network: the HTML pages inline it).
# Needs node and npm (from the npm registry, never a CDN); the versions are pinned here and in the
# bundle's README. Run from the project root: tools/viewer/build.sh
set -euo pipefail
THREE=0.187.0
ESBUILD=0.25.12
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/../../flexshaft/views/viewer/vendor"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cp "$here/entry.js" "$work/"
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --save-exact "three@$THREE" "esbuild@$ESBUILD" >/dev/null
./node_modules/.bin/esbuild entry.js --bundle --minify --format=iife --global-name=FS3 \
    --legal-comments=none --target=es2020 --outfile="$out/three-fs3.min.js"
cp node_modules/three/LICENSE "$out/THREE-LICENSE"
sha256sum "$out/three-fs3.min.js"
