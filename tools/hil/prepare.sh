#!/bin/sh
# Host preparation for `make test-hil` (docs/hil.md). Idempotent: everything it makes is cached
# under DIR (default build/hil) and remade only when missing or when the archive's kernel changed.
#
#   tools/hil/prepare.sh [DIR]
#
# 1. Debian packages (apt, Debian's archive only): qemu-system-x86, busybox-static, linux-source-6.1,
#    libgpiod-dev, libdrm-dev, cpio, kmod, and linux-headers-<ABI>-amd64 where <ABI> is the kernel
#    that linux-image-amd64 depends on, resolved now with apt-cache (not hard-coded).
# 2. That kernel's package fetched with `apt-get download` and unpacked with `dpkg -x` (not
#    installed) into DIR/kernel-<ABI>/root; its vmlinuz decompressed to an ELF (linux-source's
#    scripts/extract-vmlinux) so QEMU boots it with -kernel without the decompressor.
# 3. gpio-sim (Debian's kernel has neither CONFIG_GPIO_SIM nor CONFIG_IRQ_SIM): drivers/gpio/gpio-sim.c
#    and kernel/irq/irq_sim.c from linux-source-6.1 built as one out-of-tree module against the
#    matching headers (irq_to_desc is not exported: generic_handle_irq instead; the private
#    gpiolib.h copied beside), put in the unpacked tree's updates/ and indexed with depmod -b.
# Prints one line per step and, at the end, "hil-prepare: ABI=... KVER=... VMLINUX=... ROOT=...".
set -eu

dir=${1:-build/hil}
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
say() { echo "hil-prepare: $*"; }
die() { echo "hil-prepare: error: $*" >&2; exit 1; }

if [ "$(id -u)" -eq 0 ]; then sudo=; elif command -v sudo >/dev/null 2>&1; then sudo=sudo; else sudo=no; fi
export DEBIAN_FRONTEND=noninteractive
updated=0
apt_update() {
    [ $updated = 1 ] && return 0
    [ "$sudo" = no ] && die "not root and no sudo: cannot run apt-get update"
    $sudo apt-get update -qq || die "apt-get update failed"
    updated=1
}

# --- which kernel: what linux-image-amd64 depends on, now
abi_of() { apt-cache depends linux-image-amd64 2>/dev/null | sed -n 's/^ *Depends: linux-image-\(.*\)-amd64$/\1/p' | head -n1; }
abi=$(abi_of)
if [ -z "$abi" ]; then
    apt_update
    abi=$(abi_of)
fi
[ -n "$abi" ] || die "apt-cache depends linux-image-amd64 names no linux-image-*-amd64 package"
kver=$abi-amd64
img_pkg=linux-image-$kver
hdr_pkg=linux-headers-$kver

# --- packages (installed only when missing)
want="qemu-system-x86 busybox-static linux-source-6.1 libgpiod-dev libdrm-dev cpio kmod xz-utils make gcc libelf-dev $hdr_pkg"
missing=
for p in $want; do
    s=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
    [ "$s" = installed ] || missing="$missing $p"
done
if [ -n "$missing" ]; then
    [ "$sudo" = no ] && die "missing packages:$missing (run as root: apt-get install$missing)"
    say "installing$missing"
    apt-cache show "$hdr_pkg" >/dev/null 2>&1 || apt_update
    # shellcheck disable=SC2086
    $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null ||
        { apt_update; $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null; } ||
        die "apt-get install$missing failed"
fi
img_ver=$(apt-cache show --no-all-versions "$img_pkg" 2>/dev/null | sed -n 's/^Version: //p' | head -n1)
src_ver=$(dpkg-query -W -f='${Version}' linux-source-6.1)
hdr_ver=$(dpkg-query -W -f='${Version}' "$hdr_pkg")
[ "$hdr_ver" = "$img_ver" ] || say "warning: $hdr_pkg is $hdr_ver but $img_pkg is $img_ver"
[ "$src_ver" = "$img_ver" ] || say "warning: linux-source-6.1 is $src_ver but $img_pkg is $img_ver"

kdir=$dir/kernel-$kver-$img_ver
root=$kdir/root
mkdir -p "$kdir"

# --- kernel image and modules: apt-get download + dpkg -x (not installed)
if [ ! -f "$kdir/unpacked.stamp" ]; then
    say "fetching $img_pkg $img_ver (apt-get download) and unpacking it (dpkg -x)"
    rm -rf "$kdir/dl" "$root"
    mkdir -p "$kdir/dl"
    chmod 777 "$kdir/dl" # apt's download sandbox user writes here
    (cd "$kdir/dl" && { apt-get download -qq "$img_pkg=$img_ver" 2>&1 | grep -v 'unsandboxed as root' || true; })
    deb=$(ls "$kdir/dl/${img_pkg}_"*.deb 2>/dev/null | head -n1)
    [ -n "$deb" ] || die "apt-get download $img_pkg=$img_ver fetched nothing"
    dpkg -x "$deb" "$root"
    rm -rf "$kdir/dl"
    touch "$kdir/unpacked.stamp"
fi
[ -f "$root/boot/vmlinuz-$kver" ] || die "$root/boot/vmlinuz-$kver missing after dpkg -x"

# --- sources from linux-source-6.1 (only the files needed; the tarball is read once)
src=$dir/src-$src_ver
if [ ! -f "$src/extracted.stamp" ]; then
    tarball=$(ls /usr/src/linux-source-6.1.tar.* 2>/dev/null | head -n1)
    [ -n "$tarball" ] || die "no /usr/src/linux-source-6.1.tar.* (package linux-source-6.1)"
    say "extracting gpio-sim.c, gpiolib.h, irq_sim.c, extract-vmlinux from $(basename "$tarball")"
    rm -rf "$src"
    mkdir -p "$src"
    tar -xf "$tarball" -C "$src" --strip-components=1 \
        linux-source-6.1/drivers/gpio/gpio-sim.c linux-source-6.1/drivers/gpio/gpiolib.h \
        linux-source-6.1/kernel/irq/irq_sim.c linux-source-6.1/scripts/extract-vmlinux
    touch "$src/extracted.stamp"
fi

# --- uncompressed kernel ELF
vmlinux=$kdir/vmlinux
if [ ! -s "$vmlinux" ]; then
    say "decompressing vmlinuz-$kver (scripts/extract-vmlinux)"
    sh "$src/scripts/extract-vmlinux" "$root/boot/vmlinuz-$kver" > "$vmlinux.tmp" || die "extract-vmlinux failed"
    mv "$vmlinux.tmp" "$vmlinux"
fi

# --- gpio-sim + irq_sim as one out-of-tree module
mdir=$kdir/gpio-sim
ko=$root/lib/modules/$kver/updates/gpio-sim.ko
if [ ! -f "$ko" ]; then
    say "building gpio-sim.ko (gpio-sim.c + irq_sim.c) against $hdr_pkg"
    rm -rf "$mdir"
    mkdir -p "$mdir"
    cp "$src/drivers/gpio/gpio-sim.c" "$mdir/gpio-sim-main.c"
    cp "$src/drivers/gpio/gpiolib.h" "$mdir/"
    sed 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$src/kernel/irq/irq_sim.c" > "$mdir/irq_sim.c"
    grep -q 'generic_handle_irq(irqnum);' "$mdir/irq_sim.c" || die "irq_sim.c: the irq_to_desc call to replace was not found"
    printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' > "$mdir/Kbuild"
    make -s -C "/usr/src/linux-headers-$kver" M="$mdir" -j2 modules > "$mdir/build.log" 2>&1 ||
        { cat "$mdir/build.log" >&2; die "gpio-sim module build failed"; }
    mkdir -p "$(dirname "$ko")"
    cp "$mdir/gpio-sim.ko" "$ko"
    rm -f "$kdir/depmod.stamp"
fi
if [ ! -f "$kdir/depmod.stamp" ]; then
    say "depmod -b on the unpacked tree"
    depmod -b "$root" "$kver" || die "depmod failed"
    touch "$kdir/depmod.stamp"
fi

cat > "$dir/env" <<EOF
HIL_ABI=$abi
HIL_KVER=$kver
HIL_IMG_PKG=$img_pkg
HIL_IMG_VER=$img_ver
HIL_SRC_VER=$src_ver
HIL_HDR_VER=$hdr_ver
HIL_QEMU_VER=$(dpkg-query -W -f='${Version}' qemu-system-x86)
HIL_BUSYBOX_VER=$(dpkg-query -W -f='${Version}' busybox-static)
HIL_VMLINUX=$vmlinux
HIL_ROOT=$root
EOF
say "ABI=$abi KVER=$kver ($img_pkg $img_ver) VMLINUX=$vmlinux ROOT=$root"
