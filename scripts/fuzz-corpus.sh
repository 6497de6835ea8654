#!/usr/bin/env bash
# Builds the seed corpora of the fuzz harnesses (docs/fuzzing.md) under BUILD/corpus/<harness>/ (default
# build-fuzz; not committed): small files (at most 256 KB, 300 per harness) of each harness's format from the
# repository's scenes/, docs/ and tests/, and from ../shared/mitsuba-data when it exists. The hand-written seeds of
# tests/fuzz/seeds/ are passed to libFuzzer separately by scripts/fuzz.sh.
#
#   scripts/fuzz-corpus.sh [BUILD]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-fuzz}"
max_bytes=$((256 * 1024))
max_files=300

sources=("$root/scenes" "$root/docs" "$root/tests/data")
shared="$root/../shared/mitsuba-data"
if [ -d "$shared" ]; then sources+=("$shared"); else echo "fuzz-corpus: $shared absent, repository files only" >&2; fi

# collect HARNESS EXT... : copies files with those extensions, named by content hash (duplicates collapse).
collect() {
    local harness="$1"; shift
    local dir="$build/corpus/$harness"
    mkdir -p "$dir"
    local pattern=() ext
    for ext in "$@"; do pattern+=(-o -iname "*.$ext"); done
    find "${sources[@]}" -type f -size -"$((max_bytes + 1))"c \( -false "${pattern[@]}" \) -print0 | sort -z |
        head -z -n "$max_files" |
        while IFS= read -r -d '' file; do
            cp "$file" "$dir/$(sha1sum "$file" | cut -c1-16)"
        done
    echo "fuzz-corpus: $harness: $(find "$dir" -type f | wc -l) files in $dir"
}

collect xml xml
collect obj obj
collect ply ply
collect serialized serialized
collect exr exr
collect png png jpg jpeg bmp tga hdr
collect vol vol
collect vdb vdb
collect optimize_config json
