#!/usr/bin/env bash
# Tests of tools/veth-run (the veth runner): --check, exact exit statuses, the pair up and joined
# (an EtherType 0x88A4 frame sent on one end arrives on the other), VETH_PAIR names, bad settings
# (125), timeout (124), a nested call, and nothing left on the host. Then, when the host takes
# the netns path, the pair and a frame round trip once more through the User-Mode Linux guest
# (VETH_MODE=uml), unless VETH_TEST_UML=0.
#
#   usage: tests/tools/test_veth_run.sh
#
# The last line is "N passed, N failed"; the exit status is non-zero if anything failed.
set -u

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
VR=$root/tools/veth-run
PY=${PYTHON:-python3}
passed=0 failed=0

ok() { passed=$((passed + 1)); printf 'ok   - %s\n' "$1"; }
nok() {
    failed=$((failed + 1)); printf 'FAIL - %s\n' "$1"
    [ -z "${2:-}" ] || printf '%s\n' "$2" | sed 's/^/       | /'
}
work=$(mktemp -d "${TMPDIR:-/tmp}/test_veth_run.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT
run() { local name=$1; shift; "$@" >"$work/$name.out" 2>"$work/$name.err"; rc=$?; }
show() { printf 'rc=%s\n--- stdout\n%s\n--- stderr\n%s' "$rc" "$(cat "$work/$1.out")" "$(cat "$work/$1.err")"; }

# A frame from one end to the other: raw packet sockets for EtherType 0x88A4 on both ends,
# one EtherCAT-typed frame (a BRD datagram header) sent on $2, received on $1.
cat >"$work/wire.py" <<'EOF'
import socket, sys
rx_if, tx_if = sys.argv[1], sys.argv[2]
rx = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x88A4))
rx.bind((rx_if, 0)); rx.settimeout(5)
tx = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x88A4))
tx.bind((tx_if, 0))
payload = bytes([0x0E, 0x10, 0x07, 0x00, 0, 0, 0x30, 0x01, 2, 0, 0, 0, 0, 0, 0, 0])
frame = b"\xff" * 6 + b"\x02\x00\x00\x00\x00\x01" + b"\x88\xa4" + payload
tx.send(frame.ljust(60, b"\0"))
got = rx.recv(2048)
assert got[12:14] == b"\x88\xa4" and got[14:14 + len(payload)] == payload, got.hex()
print("frame ok")
EOF

# --------------------------------------------------------------------- --check
run check "$VR" --check
path=$(sed -n 's/^path: \([a-z]*\).*/\1/p' "$work/check.out")
if [ "$rc" = 0 ] && [[ $path =~ ^(netns|uml)$ ]] && grep -Eq '^ready: (yes|no)' "$work/check.out"; then
    ok "--check exits 0 and names the path: $path"
else
    nok "--check exits 0 and names the path" "$(show check)"
fi

# ------------------------------------------------------------- exit statuses
run true "$VR" true
[ "$rc" = 0 ] && ok "true -> 0" || nok "true -> 0" "$(show true)"
run seven "$VR" sh -c 'echo out; echo err >&2; exit 7'
if [ "$rc" = 7 ] && [ "$(cat "$work/seven.out")" = out ] && grep -qx err "$work/seven.err"; then
    ok "exit 7 passes through, stdout and stderr apart"
else
    nok "exit 7 passes through, stdout and stderr apart" "$(show seven)"
fi
run missing "$VR" /nonexistent/command
[ "$rc" = 127 ] && ok "a missing command -> 127" || nok "a missing command -> 127" "$(show missing)"

# ------------------------------------------------------------------ the pair
check_pair() { # NAME A B: both up, each the other's peer
    local a=$2 b=$3
    grep -Eq "^$a@$b +UP " "$work/$1.out" && grep -Eq "^$b@$a +UP " "$work/$1.out"
}
run pair "$VR" ip -br link
check_pair pair veth0 veth1 && ok "veth0 <-> veth1 up" || nok "veth0 <-> veth1 up" "$(show pair)"
run wire "$VR" "$PY" "$work/wire.py" veth0 veth1
if [ "$rc" = 0 ] && grep -q "frame ok" "$work/wire.out"; then
    ok "an EtherType 0x88A4 frame crosses the wire"
else
    nok "an EtherType 0x88A4 frame crosses the wire" "$(show wire)"
fi
run names env VETH_PAIR="ecm0 ecs0" "$VR" ip -br link
check_pair names ecm0 ecs0 && ok "VETH_PAIR names the pair" || nok "VETH_PAIR names the pair" "$(show names)"
run nested "$VR" "$VR" ip -br link
if [ "$rc" = 0 ] && [ "$(grep -c '^veth' "$work/nested.out")" = 2 ]; then
    ok "a nested call runs in the same pair"
else
    nok "a nested call runs in the same pair" "$(show nested)"
fi

# -------------------------------------------------------------- bad settings
for bad in "VETH_PAIR=one" "VETH_PAIR=a a" "VETH_PAIR=a;b c" "VETH_TIMEOUT=soon" "VETH_MODE=fast"; do
    run bad env "$bad" "$VR" true
    if [ "$rc" = 125 ] && [ -s "$work/bad.err" ]; then
        ok "$bad -> 125 with a message: $(head -n 1 "$work/bad.err")"
    else
        nok "$bad -> 125 with a message" "$(show bad)"
    fi
done
run noargs "$VR"
[ "$rc" = 125 ] && ok "no command -> 125" || nok "no command -> 125" "$(show noargs)"
run badopt "$VR" --frobnicate
[ "$rc" = 125 ] && ok "unknown option -> 125" || nok "unknown option -> 125" "$(show badopt)"

# ------------------------------------------------------------------- timeout
t0=$(date +%s)
run timeout env VETH_TIMEOUT=1 "$VR" sleep 30
took=$(($(date +%s) - t0))
if [ "$rc" = 124 ] && [ "$took" -lt 20 ]; then
    ok "VETH_TIMEOUT=1 stops the command: 124 after ${took}s"
else
    nok "VETH_TIMEOUT=1 stops the command: 124" "$(show timeout)"
fi

# -------------------------------------------------------- nothing left behind
if [ "$path" = netns ]; then
    if ip -br link 2>/dev/null | grep -Eq '^(veth0|veth1|ecm0|ecs0|vrprobe[01])@'; then
        nok "no interface left on the host" "$(ip -br link)"
    else
        ok "no interface left on the host"
    fi
fi

# ------------------------------------------- a user without privileges (netns)
# Where the kernel gives unprivileged user namespaces, a plain user gets the pair too.
if [ "$EUID" = 0 ] && command -v setpriv >/dev/null 2>&1 \
    && setpriv --reuid=65534 --regid=65534 --clear-groups unshare -rn true 2>/dev/null; then
    run user setpriv --reuid=65534 --regid=65534 --clear-groups env VETH_MODE=netns "$VR" ip -br link
    if [ "$rc" = 0 ] && check_pair user veth0 veth1; then
        ok "an unprivileged user gets the pair (user + network namespace)"
    else
        nok "an unprivileged user gets the pair (user + network namespace)" "$(show user)"
    fi
fi

# ------------------------------------------------------------ the uml path too
if [ "$path" = netns ] && [ "${VETH_TEST_UML:-1}" != 0 ]; then
    run uml env VETH_MODE=uml "$VR" sh -c 'ip -br link && "$0" "$1" veth0 veth1 && exit 5' \
        "$PY" "$work/wire.py"
    if [ "$rc" = 5 ] && check_pair uml veth0 veth1 && grep -q "frame ok" "$work/uml.out"; then
        ok "VETH_MODE=uml: the pair up in the guest, a frame crosses it, exit 5 passes through"
    else
        nok "VETH_MODE=uml: the pair up in the guest, a frame crosses it" "$(show uml)"
    fi
fi

echo "$passed passed, $failed failed"
[ "$failed" = 0 ]
