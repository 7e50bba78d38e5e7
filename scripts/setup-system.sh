#!/usr/bin/env bash
# Installs the system packages loudscape needs on Debian/Ubuntu, when run as root and they are
# missing; elsewhere says what to install. macOS needs only Rust and Python.
set -euo pipefail

case "$(uname -s)" in
  Darwin) exit 0 ;;
esac

# Debian package -> a file that proves it is installed.
declare -A need=(
  [mesa-vulkan-drivers]=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
  [libvulkan1]=/usr/lib/x86_64-linux-gnu/libvulkan.so.1
  [xvfb]=/usr/bin/Xvfb
  [xauth]=/usr/bin/xauth
  [imagemagick]=/usr/bin/import
  [libxkbcommon-x11-0]=/usr/lib/x86_64-linux-gnu/libxkbcommon-x11.so.0
  [libxcursor1]=/usr/lib/x86_64-linux-gnu/libXcursor.so.1
  [libxrandr2]=/usr/lib/x86_64-linux-gnu/libXrandr.so.2
  [libxi6]=/usr/lib/x86_64-linux-gnu/libXi.so.6
  [libx11-xcb1]=/usr/lib/x86_64-linux-gnu/libX11-xcb.so.1
  [libasound2-dev]=/usr/include/alsa/asoundlib.h
  [pkg-config]=/usr/bin/pkg-config
  [libsndfile1]=/usr/lib/x86_64-linux-gnu/libsndfile.so.1
  [libusb-1.0-0]=/usr/lib/x86_64-linux-gnu/libusb-1.0.so.0
  [python3-venv]=/usr/lib/python3/dist-packages/venv
  # The window tests and `make bench-window` drive the real window: xdotool, XTest, DAMAGE.
  [xdotool]=/usr/bin/xdotool
  [libxtst6]=/usr/lib/x86_64-linux-gnu/libXtst.so.6
  [libxdamage1]=/usr/lib/x86_64-linux-gnu/libXdamage.so.1
  # `loudscape video` encodes with the ffmpeg command (H.264 + AAC); its tests read back with
  # ffprobe and play under Xvfb with mpv.
  [ffmpeg]=/usr/bin/ffmpeg
  [mpv]=/usr/bin/mpv
  # The report tests read the PDF pages' text back with pdftotext.
  [poppler-utils]=/usr/bin/pdftotext
  # The web page's browser tests (tests/web/) drive Debian's chromium, headless, through Playwright.
  [chromium]=/usr/bin/chromium
)

if ! command -v dpkg >/dev/null 2>&1; then
  echo "setup: not a Debian-like system; install Vulkan drivers (or Mesa's lavapipe), Xvfb, ALSA headers and Python 3 by hand." >&2
  exit 0
fi

missing=()
for pkg in "${!need[@]}"; do
  # A package counts as present when its marker file exists or dpkg knows it installed.
  if [ -e "${need[$pkg]}" ] || dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "ok installed"; then
    continue
  fi
  missing+=("$pkg")
done

# python3-venv only matters for the system python; pyenv or other pythons bring venv along.
if python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
  missing=("${missing[@]/python3-venv}")
fi
pkgs=()
for p in "${missing[@]}"; do [ -n "$p" ] && pkgs+=("$p"); done
[ ${#pkgs[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "setup: installing ${pkgs[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
else
  echo "setup: missing system packages: ${pkgs[*]}" >&2
  echo "setup: install them with: sudo apt-get install ${pkgs[*]}" >&2
  exit 1
fi
