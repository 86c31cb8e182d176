# Shared by the CLI test scripts: source it with the pp5sim binary as $1. It sets $bin and a
# scratch folder $tmp (removed on exit), and defines fail and expect_error.
set -u
bin="$1"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

expect_error() {  # expect_error PATTERN ARGS...: a non-zero exit whose message has PATTERN
  local pattern="$1"; shift
  local out
  out=$("$bin" "$@" 2>&1) && fail "'$*' exited 0"
  echo "$out" | grep -q -- "$pattern" || fail "'$*' said: $out (expected: $pattern)"
}
