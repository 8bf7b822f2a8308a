#!/usr/bin/env bash
# Packs build/tools/uvpress and build/tests/uvpress_tests with the shared libraries they need
# into DIR (default .gpu, git-ignored), with the Vulkan loader, glvnd and the
# validation layer as Debian packages and the Duck and Fox sample assets, for a machine that
# has none of the Debian packages: a lent GPU machine, where tools/gpu-check.sh runs it.
# uvpress_tests links OpenImageIO (its reference decoder and resize), which links every codec
# plugin Debian builds (ffmpeg, OpenCV, OpenVDB, GDAL through them: ~380 MB); the tests use
# its PNG and JPEG readers and its resize only, so the plugin libraries are replaced by stubs
# that define the symbols OpenImageIO imports from them, each returning a pointer to zeros
# (its static initializers and its plugin catalogue call some: constructors, version
# strings). uvpress itself does not link OpenImageIO.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-.gpu}
stub_re='opencv|dcm|oflog|ofstd|libav|libsw|libgif|libheif|openjp2|OpenEXR|openvdb|raw_r|libtiff|libwebp|OpenColorIO|freetype'
skip_re='/(libc|libm|libpthread|libdl|librt|ld-linux-x86-64|libvulkan)\.so'
rm -rf "$out/lib" "$out/lib.tar.xz" "$out/bin" "$out/stubs"
mkdir -p "$out/lib" "$out/bin" "$out/stubs"
cp build/tools/uvpress build/tests/uvpress_tests "$out/bin/"
oiio=$(ldd build/tests/uvpress_tests | awk '/libOpenImageIO\.so/ {print $3}')
# One stub per plugin library OpenImageIO names: the symbols it imports.
for lib in $(readelf -d "$oiio" | sed -n 's/.*NEEDED.*\[\(.*\)\]/\1/p' | grep -E "$stub_re"); do
  path=$(ldd "$oiio" | awk -v l="$lib" '$1 == l {print $3}')
  # name@version pairs: the loader insists that a versioned library defines the versions asked of it.
  nm -D --defined-only "$path" | awk '{print $3}' | sed 's/@@*/ /' | sort -u >"$out/stubs/$lib.def"
  nm -D --undefined-only "$oiio" | awk '{print $2}' | sed 's/@@*/ /' | sort -u | comm -12 - "$out/stubs/$lib.def" \
    >"$out/stubs/$lib.use"
  awk 'BEGIN {print ".bss\nzeros: .zero 4096\n.text"} {printf ".globl %s\n.type %s,@function\n%s: lea zeros(%%rip), %%rax\nret\n", $1, $1, $1}' \
    "$out/stubs/$lib.use" >"$out/stubs/$lib.s"
  awk 'NF == 2 {v[$2] = v[$2] " " $1 ";"} NF == 1 {u = u " " $1 ";"}
       END {n = 0; for (k in v) {printf "%s { global:%s%s };\n", k, v[k], n++ ? "" : u}
            if (!n && u != "") printf "{ global:%s };\n", u}' "$out/stubs/$lib.use" >"$out/stubs/$lib.map"
  gcc -shared -nostdlib -Wl,-soname,"$lib" -Wl,--version-script,"$out/stubs/$lib.map" \
    -o "$out/lib/$lib" "$out/stubs/$lib.s"
done
# Everything else either binary needs, resolved with the stubs in front.
for bin in "$out"/bin/*; do
  LD_LIBRARY_PATH="$out/lib" ldd "$bin" | awk '$3 ~ /^\// {print $3}' | grep -v -E "$skip_re" | grep -v "^$PWD/$out/lib" |
    grep -v "^$out/lib" || true
done | sort -u | xargs -r -I{} cp -L -n {} "$out/lib/"
rm -rf "$out/stubs"
# Debian's packages for the machine there, downloaded (not installed) with a list of their own.
apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/gpu-bundle-lists)
if [ ! -d "$out/gl" ] || [ ! -d "$out/debs" ]; then
  mkdir -p /tmp/gpu-bundle-lists/partial "$out/gl" "$out/debs"
  apt-get "${apt_opts[@]}" update >/dev/null
  (cd "$out/gl" && apt-get "${apt_opts[@]}" download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
  (cd "$out/debs" && apt-get "${apt_opts[@]}" download vulkan-validationlayers)
fi
mkdir -p "$out/assets"
for a in Duck Fox; do
  if [ -d "../shared/assets/$a" ]; then cp -r "../shared/assets/$a" "$out/assets/"; fi
done
# The device tool carries at most 64 MiB: the libraries travel as one xz archive (~13 MB),
# unpacked there with tar -xJf DIR/lib.tar.xz -C DIR.
tar -cJf "$out/lib.tar.xz" -C "$out" lib && rm -rf "$out/lib"
du -sh "$out/bin" "$out/lib.tar.xz"
