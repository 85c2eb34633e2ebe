#!/usr/bin/env bash
# scripts/doc_commands.py on a throwaway repository: a README and a docs page whose blocks pass,
# fail, expect an exit code, share a file through /tmp/ within a page, are marked long, template or
# file, and an inline command with an unknown option; build/bin/shutterlab is a stand-in with a
# CLI11-like --help. Each failure must come back as one FILE:LINE line.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
script="$(cd "$(dirname "$0")/../.." && pwd)/scripts/doc_commands.py"
work=$(mktemp -d "${TMPDIR:-/tmp}/doc_commands_test.XXXXXX")
trap 'rm -rf "$work"' EXIT
repo="$work/repo"
mkdir -p "$repo/docs" "$repo/scripts" "$repo/build/bin" "$work/data"
echo 'the data' >"$work/data/in.txt"
printf '#!/bin/sh\necho ok\n' >"$repo/scripts/ok.sh"
cat >"$repo/build/bin/shutterlab" <<'EOF'
#!/usr/bin/env bash
# a stand-in: shutterlab greet [--name X] [--fail] [--code N] [--out F]
if [ "${1:-}" = --help ]; then
  printf 'Usage: shutterlab [OPTIONS] SUBCOMMAND\n\nOptions:\n  -h,--help  help\n\n'
  printf 'Subcommands:\n  greet      say hello\n'
  exit 0
fi
[ "${1:-}" = greet ] || { echo "no such subcommand" >&2; exit 109; }
shift
out=/dev/stdout
while [ $# -gt 0 ]; do
  case "$1" in
    --help) printf 'Usage: shutterlab greet [OPTIONS]\n\nOptions:\n  -h,--help  help\n'
            printf '  --name TEXT  who\n  --fail{false}  fail\n  --code INT  exit\n'
            printf '  --out TEXT  file\n'
            exit 0 ;;
    --name) name=$2; shift ;;
    --fail) echo "first line" >&2; echo "boom: it failed" >&2; exit 3 ;;
    --code) exit "$2" ;;
    --out) out=$2; shift ;;
    *) echo "unknown $1" >&2; exit 109 ;;
  esac
  shift
done
echo "hello ${name:-you}" >"$out"
EOF
chmod +x "$repo/scripts/ok.sh" "$repo/build/bin/shutterlab"
marker="/tmp/doc_commands_test_$$"

cat >"$repo/README.md" <<EOF
# a README

\`\`\`sh
mkdir -p $marker
build/bin/shutterlab greet --name you --out $marker/hello.txt
grep -q 'hello you' $marker/hello.txt
grep -q 'the data' \$data/in.txt && grep -q 'the data' "\$SHUTTERLAB_DATA_DIR/in.txt"
# hello you
scripts/ok.sh
build/bin/shutterlab greet --code 2    # exit code 2
\`\`\`

Inline: \`build/bin/shutterlab greet --name x\` and \`scripts/ok.sh\`.
EOF
cat >"$repo/docs/page.md" <<EOF
# a page

\`\`\`sh
mkdir -p /tmp/shared && cp \$data/in.txt /tmp/shared/copy.txt
build/bin/shutterlab greet \\
    --name me
\`\`\`

\`\`\`bash
grep -q 'the data' /tmp/shared/copy.txt   # the block before wrote it
test -f camera.json && test -f /tmp/sub/rig.json
build/bin/shutterlab greet --fail
echo never reached
\`\`\`

\`\`\`sh
build/bin/shutterlab greet --code 0    # exit code 2
\`\`\`

<!-- doc-test: long; suite: --code 4 => --code 0; 400 => 0 -->
\`\`\`sh
build/bin/shutterlab greet --code 4
sleep 400
\`\`\`

<!-- doc-test: long -->
\`\`\`sh
true
\`\`\`

<!-- doc-test: long; suite: --code 1 => --code 1 --bogus3 -->
\`\`\`sh
build/bin/shutterlab greet --code 1
\`\`\`

<!-- doc-test: long; suite: --code 0 => --code 1; --nowhere => --code 0 -->
\`\`\`sh
build/bin/shutterlab greet --code 0
\`\`\`

<!-- doc-test: template -->
\`\`\`sh
build/bin/shutterlab greet DATASET --bogus
build/bin/missing_tool --x
\`\`\`

<!-- doc-test: file camera.json -->
\`\`\`json
{"format": "rig/1"}
\`\`\`

<!-- doc-test: file /tmp/sub/rig.json -->
\`\`\`json
{}
\`\`\`

| command | what |
| --- | --- |
| \`build/bin/shutterlab greet --nope \\| cat\` | an unknown option |
| \`build/bin/shutterlab wave\` | an unknown subcommand |
| \`shutterlab greet [--name X \\| --nope2] [--code 0\\|2]\` | a synopsis |

\`\`\`
scripts/ok.sh --no-language
\`\`\`
EOF

# A mistyped long mark, a pair whose text is only in a comment, a smaller block that fails, a
# script that exits 77 (a tool missing), and a benchmark this build lacks with a block after it.
mkdir -p "$repo/bench"
touch "$repo/bench/tool_bench.cc"
echo "SHUTTERLAB_BUILD_BENCH:BOOL=OFF" >"$repo/build/CMakeCache.txt"
cat >"$repo/docs/more.md" <<'EOF'
# more

<!-- doc-test: long suite: --code 3 => --code 0 -->
```sh
build/bin/shutterlab greet --code 3
```

<!-- doc-test: long; suite: 15 => 2 -->
```sh
# shows 15 frames
build/bin/shutterlab greet --code 0
```

<!-- doc-test: long; suite: --code 5 => --code 6 -->
```sh
build/bin/shutterlab greet --code 5   # takes 5 minutes
```

```sh
build/bin/shutterlab greet --code 77
echo never reached
```

```sh
build/bin/tool_bench --keep /tmp/x
```

```sh
cat /tmp/x/out.txt
```
EOF

# run ARGS...: the script's output in $got, its exit status in $status
run() { status=0; got=$(/usr/bin/python3 "$script" --root "$repo" "$@" 2>&1) || status=$?; }
has() { grep -qF -- "$1" <<<"$got" || fail "no '$1' in the output:
$got"; }

export SHUTTERLAB_DATA_DIR="$work/data"
unset CI
run --verbose
[ "$status" = 1 ] || fail "exit $status, not 1:
$got"
has "docs/page.md:12: build/bin/shutterlab greet --fail: exit code 3: first line | boom: it failed"
has "docs/page.md:17: build/bin/shutterlab greet --code 0: exit code 0 (expected 2): (no stderr)"
has "docs/page.md:43: shutterlab greet has no option --bogus"
has "docs/page.md:44: build/bin/missing_tool is not in the build folder"
has "docs/page.md:59: shutterlab greet has no option --nope"
has "docs/page.md:60: shutterlab has no subcommand 'wave'"
has "docs/page.md:61: shutterlab greet has no option --nope2"
has "docs/page.md:63: a command in a fence with no language"
# A long block runs smaller in the suite (--code 4 made 0, sleep 400 made 0); a bare long mark, a
# pair whose text is not in the block are refused; what the pairs make is checked too.
has "docs/page.md:21:    0.0 s (long, run smaller)"
has "docs/page.md:26: a long block says how the suite runs it smaller"
has "docs/page.md:33: shutterlab greet has no option --bogus3 (not in its --help): build/bin/shutterlab greet --code 1 --bogus3 (as the suite runs it)"
has "docs/page.md:36: '--nowhere => --code 0' is not TEXT => REPLACEMENT"
has "docs/page.md:42: not run (marked template)"
# README.md passes: its one line is its block's time; page.md: 6 blocks' lines and 12 findings.
[ "$(grep -c '^README.md:' <<<"$got")" = 1 ] && ! grep -q '^README.md:.*FAILED' <<<"$got" ||
  fail "README.md must pass:
$got"
[ "$(grep -c '^docs/page.md:[0-9]*: ' <<<"$got")" = 18 ] || fail "not one line per finding:
$got"
[ ! -e "$marker" ] || { rm -rf "$marker"; fail "a block wrote to the real /tmp"; }
[ ! -e "$repo/camera.json" ] || fail "a file block was written into the repository"

# more.md: each case in one line; exit 77 a skip, but a failure under CI=true.
has "docs/more.md:3: unknown mark '<!-- doc-test: long suite: --code 3 => --code 0 -->'"
has "docs/more.md:8: '15 => 2' is not TEXT => REPLACEMENT with TEXT in a command"
has "docs/more.md:16: build/bin/shutterlab greet --code 6: exit code 6: (no stderr) (as the suite runs it)"
has "docs/more.md:20: build/bin/shutterlab greet --code 77: exit code 77, a tool it needs is missing"
has "docs/more.md:19:    0.0 s  SKIPPED"
has "docs/more.md:24: not run (build/bin/tool_bench is not built here)"
has "docs/more.md:28: not run (it may read what line 24 wrote, which did not run)"
[ "$(grep -c '^docs/more.md:[0-9]*: ' <<<"$got")" = 8 ] || fail "more.md: not one line per case:
$got"
CI=true run docs/more.md
[ "$status" = 1 ] || fail "exit $status under CI=true, not 1:
$got"
has "docs/more.md:20: build/bin/shutterlab greet --code 77: exit code 77, a tool it needs is missing: (no stderr) (CI=true needs it)"

# The long block runs as written with --long (and fails: --code 4).
run --long docs/page.md
has "docs/page.md:22: build/bin/shutterlab greet --code 4: exit code 4"

# Without the shared data: only checked; a skip (77), a failure under CI=true.
rm "$repo/docs/page.md" "$repo/docs/more.md"
export SHUTTERLAB_DATA_DIR="$work/no data"
run
[ "$status" = 77 ] || fail "exit $status without the data, not 77:
$got"
has "is absent"
CI=true run
[ "$status" = 1 ] || fail "exit $status without the data under CI=true, not 1:
$got"
echo "doc_commands_test: ok"
