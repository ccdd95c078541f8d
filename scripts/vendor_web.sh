#!/usr/bin/env bash
# Refetch the sky chart's vendored code and data from the npm registry, reproducibly: pinned
# versions, checked against the SHA-256 of each package's tarball, then reduced by
# scripts/vendor_web_reduce.js into src/scopelink/web/static/{vendor,sky}/ (docs/dashboard.md,
# "Sky chart"). Needs npm and node; nothing of this runs at install or run time.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
STATIC="$ROOT/src/scopelink/web/static"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

# name@version sha256-of-the-tarball
PACKAGES=(
  "d3-array@3.2.4 6dbf3f2be39e48f86775be6e166a5d3e5a585ca7144453cd6ad1912f5ae4417f"
  "d3-geo@3.1.2 e0ffa43f5a2134cf03d2797e985025250d8d3608b1d90336938c9dd4d4b97dc7"
  "d3-celestial@0.7.35 490796718c201e15f38c324bda5458fc4de22519313093bf261b628185eaae81"
)

cd "$WORK"
for entry in "${PACKAGES[@]}"; do
  read -r spec sha <<<"$entry"
  name="${spec%@*}"
  tarball="$(npm pack --silent "$spec" 2>/dev/null | tail -n 1)"
  echo "$sha  $tarball" | sha256sum --check --quiet
  mkdir -p "$name"
  tar xzf "$tarball" -C "$name"
done

mkdir -p "$STATIC/vendor" "$STATIC/sky"
cp d3-array/package/dist/d3-array.min.js d3-geo/package/dist/d3-geo.min.js "$STATIC/vendor/"
node "$ROOT/scripts/vendor_web_reduce.js" "$WORK" "$STATIC/sky"
echo "vendored into $STATIC/vendor and $STATIC/sky:"
ls -l "$STATIC/vendor" "$STATIC/sky"
