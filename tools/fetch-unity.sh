#!/bin/sh
# tools/fetch-unity.sh DEST - extract Unity (MIT, ThrowTheSwitch) from Debian's 'cmock' binary
# package into DEST/src. Nothing is installed and the system's apt configuration is left alone: a
# private apt configuration in a temporary folder reads Debian trixie's package lists.
# The pinned version is verified by SHA256. When that version has left the archive, the version
# the archive serves now is taken instead, checked to contain unity.c, and the script says so.
set -eu
DEST=${1:?usage: fetch-unity.sh DEST}
CMOCK_VERSION=${CMOCK_VERSION:-2.5.3+git40-g379a9a8-2}
CMOCK_SHA256=${CMOCK_SHA256:-166e45090937251892363d10860b5e7aa5353d5553fde2cbaba514760ba3785e}
KEYRING=/usr/share/keyrings/debian-archive-keyring.gpg

T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT INT TERM
mkdir -p "$T/parts" "$T/lists/partial" "$T/cache/archives/partial" "$T/dl"
: >"$T/status"
cat >"$T/parts/trixie.sources" <<SRC
Types: deb
URIs: http://deb.debian.org/debian
Suites: trixie
Components: main
Signed-By: $KEYRING
SRC
set -- -o Dir::Etc::SourceList=/dev/null -o Dir::Etc::SourceParts="$T/parts" \
    -o Dir::State::Lists="$T/lists" -o Dir::Cache="$T/cache" \
    -o Dir::State::status="$T/status" -o Acquire::Languages=none -o APT::Sandbox::User=root \
    -o Acquire::IndexTargets::deb::Contents-deb::DefaultEnabled=false
apt-get "$@" update >"$T/update.log" 2>&1 || { cat "$T/update.log" >&2; exit 1; }

if (cd "$T/dl" && apt-get "$@" download "cmock=$CMOCK_VERSION" >/dev/null 2>&1); then
    DEB=$(ls "$T"/dl/cmock_*_all.deb)
    if ! echo "$CMOCK_SHA256  $DEB" | sha256sum -c - >/dev/null 2>&1; then
        echo "fetch-unity: SHA256 mismatch for cmock $CMOCK_VERSION: refusing it" >&2
        exit 1
    fi
else
    echo "fetch-unity: WARNING: cmock $CMOCK_VERSION has left the archive; taking the version" \
        "the archive serves now (not verified by a pinned hash)" >&2
    (cd "$T/dl" && apt-get "$@" download cmock >/dev/null)
    DEB=$(ls "$T"/dl/cmock_*_all.deb)
    echo "fetch-unity: took $(basename "$DEB"), SHA256 $(sha256sum "$DEB" | cut -d' ' -f1)" >&2
fi
dpkg-deb -x "$DEB" "$T/x"
U="$T/x/usr/share/cmock/vendor/unity"
if [ ! -f "$U/src/unity.c" ]; then
    echo "fetch-unity: $(basename "$DEB") has no vendor/unity/src/unity.c" >&2
    exit 1
fi
mkdir -p "$DEST/src"
cp "$U/src/unity.c" "$U/src/unity.h" "$U/src/unity_internals.h" "$DEST/src/"
cp "$U/LICENSE.txt" "$DEST/"
grep -E 'define UNITY_VERSION_(MAJOR|MINOR|BUILD)' "$DEST/src/unity.h"
