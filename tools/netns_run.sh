#!/usr/bin/env bash
# Every camera of a dataset as a `netvmo node` in a Linux network namespace of its own, as on
# separate machines (docs/processes.md, "Several machines, emulated"): each namespace has one
# veth interface, eth0, joined to a bridge in a namespace of the harness's own, and an address
# of 198.18.<n>.0/24 (RFC 2544's benchmarking range) that exists only inside these namespaces;
# each node's Cyclone DDS configuration is datasets/cyclonedds_multihost.template.xml with eth0
# and every camera's address as the peers (unicast, multicast off), as a user would fill it in.
# Then the nodes' files are gathered and merged with `netvmo merge`, as from several machines.
#
#   tools/netns_run.sh NETVMO DATASET OUT [options] [-- node options]
#     --mode lockstep|async   (default lockstep)
#     --loss PCT              every namespace drops PCT % of its incoming packets (nftables,
#                             numgen random), from the start; OUT/loss.txt: per camera, its
#                             packets in and dropped
#     --cut ID@T:D            the bridge forwards nothing to or from camera ID from T to T+D
#                             seconds after the start (async: the common start, once every
#                             node is ready) (nftables in the bridge's namespace)
#                             (async: a partition; cameras behind it are isolated);
#                             OUT/events.txt: the start's, the cut's and the heal's
#                             wall-clock times [s], one per line ("start T", "cut ID T",
#                             "healed ID T"; the cut's and the heal's once nftables has them)
#     --delay MS:JITTER       every namespace delays its outgoing packets MS +- JITTER ms
#                             (tc netem); exits 77 where the kernel has no netem
#     --timeout S             every node is killed after S seconds (default 120)
#     --clock-offsets ID:S,...  camera ID's node runs as on a host whose clock is S seconds off
#                             (node --clock-offset; the namespaces share this machine's clock)
#
# Needs root, `ip netns` and, for --loss and --cut, nft. Exits 77 (with the reason on stderr) when this
# machine does not allow network namespaces. Removes every namespace it made on every path
# (exit, error, SIGINT, SIGTERM).
set -euo pipefail

usage() { echo "usage: tools/netns_run.sh NETVMO DATASET OUT [--mode M] [--loss PCT] [--cut ID@T:D] [--delay MS:J] [--clock-offsets ID:S,...] [--timeout S] [-- node options]" >&2; exit 2; }
[ $# -ge 3 ] || usage
netvmo=$(realpath "$1"); dataset=$(realpath "$2"); out=$3; shift 3
mode=lockstep loss=0 cut="" delay="" timeout=120
node_args=()
declare -A clock_offset=()
while [ $# -gt 0 ]; do
  case $1 in
    --mode) mode=$2; shift 2 ;;
    --loss) loss=$2; shift 2 ;;
    --cut) cut=$2; shift 2 ;;
    --delay) delay=$2; shift 2 ;;
    --timeout) timeout=$2; shift 2 ;;
    --clock-offsets)
      IFS=, read -ra items <<<"$2"
      for item in "${items[@]}"; do
        [[ $item =~ ^([0-9]+):(-?[0-9.]+)$ ]] || { echo "netns_run: --clock-offsets $2: '$item' is not ID:SECONDS" >&2; exit 2; }
        clock_offset[${BASH_REMATCH[1]}]=${BASH_REMATCH[2]}
      done
      shift 2 ;;
    --) shift; node_args=("$@"); break ;;
    *) usage ;;
  esac
done
here=$(cd "$(dirname "$0")/.." && pwd)
template=$here/datasets/cyclonedds_multihost.template.xml

if [ "$(id -u)" != 0 ]; then echo "netns_run: needs root (ip netns)" >&2; exit 77; fi
tag=nv$$
namespaces=()
pids=()
cleanup() {  # every process inside the namespaces (the nodes), the harness's own, the namespaces
  for ns in "${namespaces[@]:-}"; do
    [ -n "$ns" ] && ip netns pids "$ns" 2>/dev/null | xargs -r kill -KILL 2>/dev/null || true
  done
  for p in "${pids[@]:-}"; do [ -n "$p" ] && kill -KILL "$p" 2>/dev/null || true; done
  for ns in "${namespaces[@]:-}"; do [ -n "$ns" ] && ip netns del "$ns" 2>/dev/null || true; done
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
probe=${tag}probe
namespaces+=("$probe")
if ! ip netns add "$probe" 2>/dev/null; then
  echo "netns_run: this machine does not allow network namespaces (ip netns add failed)" >&2
  exit 77
fi
# What the harness needs inside a namespace: a veth pair, a bridge and nftables.
why=""
ip -n "$probe" link add va type veth peer name vb 2>/dev/null || why="no veth pairs"
[ -n "$why" ] || ip -n "$probe" link add vbr type bridge 2>/dev/null || why="no bridges"
[ -n "$why" ] || command -v nft > /dev/null || why="no nft (Debian's nftables)"
[ -n "$why" ] || ip netns exec "$probe" nft list ruleset > /dev/null 2>&1 || why="nftables refused"
if [ -z "$why" ] && [ -n "$delay" ] &&
   ! ip netns exec "$probe" tc qdisc add dev va root netem delay 1ms > /dev/null 2>&1; then
  why="no netem in this kernel (tc qdisc add ... netem: $(ip netns exec "$probe" tc qdisc add dev va root netem delay 1ms 2>&1 | head -n 1 || true))"
fi
ip netns del "$probe"
if [ -n "$why" ]; then echo "netns_run: network namespaces without what the harness needs: $why" >&2; exit 77; fi

# The cameras of network.yaml, in order ("- id: N" or "- {id: N").
mapfile -t ids < <(grep -oE '^[[:space:]]*-[[:space:]]*\{?[[:space:]]*id:[[:space:]]*[0-9]+' \
  "$dataset/network.yaml" | grep -oE '[0-9]+$')
[ ${#ids[@]} -ge 1 ] || { echo "netns_run: $dataset/network.yaml: no cameras" >&2; exit 2; }
for c in "${!clock_offset[@]}"; do
  [[ " ${ids[*]} " == *" $c "* ]] || { echo "netns_run: --clock-offsets: no camera $c in $dataset/network.yaml" >&2; exit 2; }
done
net=198.18.$(( $$ % 250 ))
bridge=${tag}br

ip netns add "$bridge"; namespaces+=("$bridge")
ip -n "$bridge" link add br0 type bridge
ip -n "$bridge" link set br0 up
peers=""
for k in "${!ids[@]}"; do peers+="        <Peer Address=\"$net.$((k + 1))\" />\n"; done
mkdir -p "$out/nodes"
for k in "${!ids[@]}"; do
  id=${ids[$k]} ns=${tag}c${ids[$k]}
  ip netns add "$ns"; namespaces+=("$ns")
  ip -n "$bridge" link add "p$k" type veth peer name eth0 netns "$ns"
  ip -n "$bridge" link set "p$k" master br0 up
  ip -n "$ns" addr add "$net.$((k + 1))/24" dev eth0
  ip -n "$ns" link set eth0 up
  ip -n "$ns" link set lo up
  if [ -n "$delay" ]; then
    ip netns exec "$ns" tc qdisc add dev eth0 root netem delay "${delay%:*}ms" "${delay#*:}ms"
  fi
  if [ "$loss" != 0 ]; then
    ip netns exec "$ns" nft add table inet netvmo_loss
    ip netns exec "$ns" nft add chain inet netvmo_loss input '{ type filter hook input priority 0; }'
    ip netns exec "$ns" nft add rule inet netvmo_loss input iifname eth0 counter
    ip netns exec "$ns" nft add rule inet netvmo_loss input iifname eth0 numgen random mod 100 \< "$loss" counter drop
  fi
  # The template as a user fills it in: this machine's interface, every machine as a peer.
  awk -v peers="$peers" '
    /<NetworkInterface name=/ { sub(/NETWORK_INTERFACE/, "eth0") }
    /<Peer Address=.*PEER_ADDRESS_/ { if (!done) { printf "%s", peers; done = 1 } next }
    { print }' "$template" | sed 's/\\n/\n/g' > "$out/cyclonedds_$id.xml"
done

domain=$(( 1 + $$ % 200 ))
start_args=()
start_file=""
if [ "$mode" = async ]; then
  # The common start once every node is set up and has matched its neighbours (node
  # --start-file, as `netvmo launch` does). A fixed start a few seconds ahead made a node whose
  # discovery took longer join late, at its next image: under 10 % loss a lost discovery message
  # is sent again seconds later (8.1 s for two nodes in 1 of 25 runs, 2026-12-05).
  start_file="$(realpath "$out")/start.txt"
  rm -f "$start_file" "$out"/node_*.ready
  start_args=(--start-file "$start_file")
fi
for k in "${!ids[@]}"; do
  id=${ids[$k]} ns=${tag}c${ids[$k]}
  clock_args=()
  if [ -n "${clock_offset[$id]:-}" ]; then clock_args=(--clock-offset "${clock_offset[$id]}"); fi
  ip netns exec "$ns" env CYCLONEDDS_URI="file://$(realpath "$out/cyclonedds_$id.xml")" \
    timeout -k 5 "$timeout" "$netvmo" node "$dataset" --camera "$id" --out "$out/node_$id" \
    --domain "$domain" --mode "$mode" "${start_args[@]}" "${clock_args[@]}" "${node_args[@]}" \
    > "$out/node_$id.log" 2>&1 &
  pids+=($!)
done

# Async: every node ready (or one ended, or --timeout passed), then the common start, 0.25 s
# ahead (launch's margin), written whole (renamed into place).
start=$(date +%s.%N)
if [ -n "$start_file" ]; then
  give_up=$(( $(date +%s) + timeout ))
  while :; do
    ready=1 ended=0
    for k in "${!ids[@]}"; do
      [ -e "$out/node_${ids[$k]}.ready" ] || ready=0
      kill -0 "${pids[$k]}" 2>/dev/null || ended=1
    done
    if [ "$ready" = 1 ] || [ "$ended" = 1 ] || [ "$(date +%s)" -gt "$give_up" ]; then break; fi
    sleep 0.01
  done
  start=$(date +%s.%N | awk '{printf "%.3f", $1 + 0.25}')
  echo "$start" > "$start_file.partial" && mv "$start_file.partial" "$start_file"
fi

if [ -n "$cut" ]; then  # ID@T:D
  cut_id=${cut%@*} rest=${cut#*@}; cut_at=${rest%:*} cut_for=${rest#*:}
  for k in "${!ids[@]}"; do [ "${ids[$k]}" = "$cut_id" ] && cut_k=$k; done
  [ -n "${cut_k:-}" ] || { echo "netns_run: --cut $cut: no camera $cut_id" >&2; exit 2; }
  echo "start $start" > "$out/events.txt"
  ( sleep "$(awk -v t="$cut_at" -v s="$start" -v now="$(date +%s.%N)" \
      'BEGIN { d = s + t - now; print (d > 0 ? d : 0) }')"
    # The switch stops forwarding the camera's port (its own link stays up, as when a network
    # beyond the camera fails; a link without carrier would instead block its sends).
    ip netns exec "$bridge" nft add table bridge netvmo_cut
    ip netns exec "$bridge" nft add chain bridge netvmo_cut forward \
      '{ type filter hook forward priority 0; }'
    ip netns exec "$bridge" nft add rule bridge netvmo_cut forward iifname "p$cut_k" drop
    ip netns exec "$bridge" nft add rule bridge netvmo_cut forward oifname "p$cut_k" drop
    echo "cut $cut_id $(date +%s.%N)" >> "$out/events.txt"
    sleep "$cut_for"
    ip netns exec "$bridge" nft delete table bridge netvmo_cut
    echo "healed $cut_id $(date +%s.%N)" >> "$out/events.txt" ) &
  pids+=($!)
fi

failed=0
for k in "${!ids[@]}"; do
  if ! wait "${pids[$k]}"; then
    echo "netns_run: node of camera ${ids[$k]} failed: $(tail -n 1 "$out/node_${ids[$k]}.log")" >&2
    failed=1
  fi
done
[ -z "$cut" ] || wait "${pids[-1]}" || true
if [ "$loss" != 0 ]; then  # per camera: packets in, packets dropped (the two counters)
  for id in "${ids[@]}"; do
    echo "$id $(ip netns exec "${tag}c$id" nft list table inet netvmo_loss |
      grep -oE 'packets [0-9]+' | awk '{printf "%s ", $2}')" >> "$out/loss.txt"
  done
fi
[ $failed = 0 ] || exit 1
# Gathered from the "machines", merged as `netvmo merge` does for several machines.
for id in "${ids[@]}"; do cp "$out/node_$id"/node_"$id".csv "$out/node_$id"/node_"$id".json \
  "$out/node_$id"/node_"$id"_links.csv "$out/nodes/"; done
"$netvmo" merge "$out/nodes" --dataset "$dataset" --out "$out/merged" --no-plots --no-overlays \
  > "$out/merge.log" 2>&1 || { echo "netns_run: merge failed: $(tail -n 1 "$out/merge.log")" >&2; exit 1; }
echo "netns_run: ${#ids[@]} nodes in namespaces, $mode, loss $loss %, merged into $out/merged"
