#!/bin/sh
# Installs the Debian (bookworm) packages fovea needs, only when missing. Idempotent; silent when
# everything is present. --cross adds the aarch64 cross toolchain, qemu-user and arm64 libraries
# (through dpkg multiarch) for the cross leg; --bench adds gnuplot for the charts of `make bench`
# (not needed by `make test`); --fuzz adds clang and its libFuzzer runtime for `make fuzz`.
set -eu
native="g++ make pkg-config libembree-dev libtinygltf-dev libstb-dev libcmocka-dev libjpeg62-turbo-dev
        libgpiod-dev libdrm-dev libsdl2-dev"
cross="gcc-aarch64-linux-gnu g++-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user
       libembree-dev:arm64 libtinygltf-dev:arm64 libstb-dev:arm64 libcmocka-dev:arm64 libjpeg62-turbo-dev:arm64"
want=$native
[ "${1:-}" = "--cross" ] && want="$native $cross"
[ "${1:-}" = "--bench" ] && want="$native gnuplot-nox"
[ "${1:-}" = "--fuzz" ] && want="$native clang libclang-rt-14-dev"

arch=$(dpkg --print-architecture)
missing=
for p in $want; do
    # With arm64 libraries installed too, a bare name is ambiguous: ask for the native one first.
    case "$p" in *:*) q=$p ;; *) q="$p:$arch" ;; esac
    s=$(dpkg-query -W -f='${db:Status-Status}' "$q" 2>/dev/null || dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
    [ "$s" = installed ] || missing="$missing $p"
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -eq 0 ]; then sudo=; elif command -v sudo >/dev/null 2>&1; then sudo=sudo; else
    echo "deps: missing packages:$missing; run as root: apt-get install$missing" >&2
    exit 1
fi
echo "deps: installing$missing"
case "$missing" in *:arm64*)
    dpkg --print-foreign-architectures | grep -qx arm64 || $sudo dpkg --add-architecture arm64 ;;
esac
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
# shellcheck disable=SC2086
$sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
