#!/usr/bin/env bash
# Fetch a few freely licensed game soundtracks from Debian packages for the real-music tests
# (preprocess/tests/test_real_music.py). `apt-get download` only: nothing is installed. The
# packages are unpacked with dpkg-deb -x into the ignored folder data/real-music/ (about 21 MB
# of packages), with each package's copyright file beside its music. Licences:
# docs/REAL_MUSIC.md.
#
#   scripts/fetch-real-music.sh [DEST]     (default data/real-music)
#
# Cached: a package already unpacked is not fetched again. Exits non-zero with one clear
# line when a download fails, so `make test` does not silently skip the tests.
set -euo pipefail

dest="${1:-data/real-music}"
# Debian package -> the music files the tests use (paths inside the package).
declare -A files=(
  [rrootage-data]="usr/share/games/rrootage/sounds/stg_a.ogg usr/share/games/rrootage/sounds/stg_b.ogg"
  [torus-trooper-data]="usr/share/games/torus-trooper/sounds/musics/tt1.ogg usr/share/games/torus-trooper/sounds/musics/tt3.ogg"
  [hex-a-hop-data]="usr/share/games/hex-a-hop/hex-a-hop/music-ending.ogg"
  [holotz-castle-data]="usr/share/games/holotz-castle/game/sound/HCMainTitle.wav usr/share/games/holotz-castle/game/sound/HCCredits_Slow.wav"
)

missing=()
for pkg in "${!files[@]}"; do
  for f in ${files[$pkg]}; do
    [ -s "$dest/$pkg/$(basename "$f")" ] || { missing+=("$pkg"); break; }
  done
done
if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi

for tool in apt-get dpkg-deb; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "fetch-real-music: $tool not found: the real-music tests need a Debian-like system (packages: ${missing[*]})" >&2
    exit 1
  fi
done

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
if [ "$(id -u)" -eq 0 ]; then
  apt-get update -qq >/dev/null 2>&1 || echo "fetch-real-music: apt-get update failed; trying the package lists there are" >&2
fi
for pkg in "${missing[@]}"; do
  if ! (cd "$work" && apt-get download -qq "$pkg" >/dev/null 2>"$work/$pkg.err"); then
    echo "fetch-real-music: cannot download Debian package $pkg: $(tr '\n' ' ' < "$work/$pkg.err")" >&2
    exit 1
  fi
  deb="$(ls "$work"/"${pkg}"_*.deb)"
  mkdir -p "$work/$pkg.x" "$dest/$pkg"
  dpkg-deb -x "$deb" "$work/$pkg.x"
  for f in ${files[$pkg]}; do
    if [ ! -s "$work/$pkg.x/$f" ]; then
      echo "fetch-real-music: $pkg ($(basename "$deb")) has no $f" >&2
      exit 1
    fi
    cp "$work/$pkg.x/$f" "$dest/$pkg/"
  done
  cp "$work/$pkg.x/usr/share/doc/$pkg/copyright" "$dest/$pkg/copyright"
  basename "$deb" > "$dest/$pkg/PACKAGE"
  echo "fetch-real-music: $pkg -> $dest/$pkg" >&2
done
