#!/usr/bin/env bash
# A new user's mistakes on the command line (issue 18): a sentence with a suggestion and exit
# status 2, never the argument parser's own codes; --version.
. "$(dirname "$0")/cli_lib.sh"
status_of() { "$bin" "$@" >/dev/null 2>&1; echo $?; }

expect_error "unknown command 'rendr'; did you mean 'render'?" rendr
expect_error "unknown option '--sceen'; did you mean '--scene'?" render --sceen torus
expect_error "unknown command 'frobnicate'" frobnicate
expect_error "--threads: Value 0 not in range 1 to 256" render --threads 0 --out "$tmp/x"
for args in "rendr" "render --sceen torus" "render --threads 0" "sweep --grid"; do
  # shellcheck disable=SC2086
  [ "$(status_of $args)" = 2 ] || fail "'$args' should exit 2, exited $(status_of $args)"
done
"$bin" --version | grep -q "^pp5sim [0-9]" || fail "--version printed: $("$bin" --version)"
[ "$(status_of --help)" = 0 ] || fail "--help should exit 0"
[ -e "$tmp/x" ] && fail "a usage error wrote output"
echo "usage_cli: all checks passed"
