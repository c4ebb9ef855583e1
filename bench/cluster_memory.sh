#!/usr/bin/env bash
# Peak memory per rank of `mpirun -np P sdftrace bake` against one process (docs/cluster.md,
# "Memory and time against ranks"): P = 1, 2, 4, 8 ranks with one thread each (more ranks than
# cores oversubscribe, so the times say little; memory is the figure that counts here), each
# rank's peak resident memory from /usr/bin/time, the largest of them against the single process's
# peak, and the wall time. The outputs are checked against the single process's samples
# (`convert --uncompressed` of both is the same file).
#   bash bench/cluster_memory.sh [path/to/sdftrace]
#   MESHES="a.ply:2048 b.obj:1024" to choose meshes and resolutions (default: the repository's
#   meshes and, when scripts/make-scale-meshes.sh has made it, its million-triangle rock);
#   RANKS="1 2 4" for other rank counts.
set -euo pipefail
cli=$(realpath "${1:-build/release/apps/sdftrace/sdftrace}")
root=$(cd "$(dirname "$0")/.." && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

default="$root/data/meshes/stanford-bunny.obj:1024 $root/data/meshes/elephant-with-holes.obj:1024"
rock=/tmp/sdftrace-meshes/rock.ply
[ -f "$rock" ] && default="$default $rock:1024 $rock:2048"
meshes=${MESHES:-$default}
ranks=${RANKS:-1 2 4 8}

echo "| mesh | triangles | cells | ranks | peak per rank, MiB (largest) | vs one process | rank 0 | wall s | samples |"
echo "|---|---|---|---|---|---|---|---|---|"
for m in $meshes; do
    mesh=${m%:*} res=${m##*:}
    name=$(basename "$mesh")
    # One process, no mpirun: the baseline.
    /usr/bin/time -f '%M %e' -o "$out/one.time" "$cli" bake "$mesh" --res "$res" --threads 1 -q \
        -o "$out/one.sdfg" 2>"$out/one.log"
    read -r one_kb one_s <"$out/one.time"
    tris=$(grep -oE '[0-9]+ triangles' "$out/one.log" | head -1 | grep -oE '[0-9]+')
    "$cli" convert "$out/one.sdfg" "$out/one-raw.sdfg" --uncompressed >/dev/null 2>&1
    printf '| %s | %s | %s | 1 process | %.0f | 1.00 | — | %.1f | — |\n' "$name" "$tris" "$res" \
        "$(echo "$one_kb / 1024" | bc -l)" "$one_s"
    for p in $ranks; do
        rm -f "$out"/rank.*
        t0=$(date +%s.%N)
        mpirun -np "$p" bash -c "/usr/bin/time -f %M -o $out/rank.\$OMPI_COMM_WORLD_RANK $cli bake \
            $mesh --res $res --threads 1 -q -o $out/many.sdfg" >"$out/many.log" 2>&1
        t1=$(date +%s.%N)
        largest=$(cat "$out"/rank.* | sort -n | tail -1)
        "$cli" convert "$out/many.sdfg" "$out/many-raw.sdfg" --uncompressed >/dev/null 2>&1
        same=$(cmp -s "$out/one-raw.sdfg" "$out/many-raw.sdfg" && echo same || echo DIFFER)
        printf '| %s | %s | %s | %d | %.0f | %.2f | %.0f | %.1f | %s |\n' "$name" "$tris" "$res" "$p" \
            "$(echo "$largest / 1024" | bc -l)" "$(echo "$largest / $one_kb" | bc -l)" \
            "$(echo "$(cat "$out/rank.0") / 1024" | bc -l)" "$(echo "$t1 - $t0" | bc -l)" "$same"
    done
done
