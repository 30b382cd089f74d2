#!/bin/sh
# Every command the documentation shows, run (docs/testing.md, "Documentation
# that runs"): each line of a fenced `sh` block of README.md and docs/*.md (a
# line ending in a backslash continues on the next) runs with `sh -c`, one
# file's blocks in order in one scratch directory holding build/rtsim, links to
# configs/ and scenes/, and a link to one copy of results/. A block right after a line
# `<!-- not run: REASON -->` is skipped. A failing command fails the test with
# FILE:LINE, its exit code and its output.
#   usage: sh tests/doc_commands.sh SOURCE_DIR RTSIM SCRATCH
# The script first checks itself on a made-up page whose second command fails,
# so that a runner that ran nothing, or lost the line, fails too.
set -eu
src=$1 rtsim=$2 scratch=$3

# The commands of FILE, one a line: "LINE<TAB>COMMAND" (LINE is where it starts).
# A not-run marker without a reason, or a block left open, is an error.
extract() {
  awk '
  function flush() { if (cmd != "") print start "\t" cmd; cmd = "" }
  /^```/ {
    if (!inblock) {
      inblock = 1; run = ($0 == "```sh") && !skip; skip = 0; open = NR; next
    }
    if (cont) { printf "%s:%d: a command continues past its block\n", FILENAME, start > "/dev/stderr"; bad = 1 }
    flush(); inblock = 0; cont = 0; run = 0; next
  }
  inblock && run {
    line = $0
    if (!cont) { if (line ~ /^[ \t]*$/) next; start = NR; cmd = "" }
    if (line ~ /\\$/) { cmd = cmd substr(line, 1, length(line) - 1); cont = 1; next }
    cmd = cmd line; cont = 0; flush(); next
  }
  inblock { next }
  /^<!-- not run:/ {
    if ($0 !~ /^<!-- not run: [^ ].*-->$/) { printf "%s:%d: a not-run marker needs a reason\n", FILENAME, NR > "/dev/stderr"; bad = 1 }
    skip = 1; next
  }
  /^[ \t]*$/ { next }
  { skip = 0 }
  END {
    if (inblock) { printf "%s:%d: a block is never closed\n", FILENAME, open > "/dev/stderr"; bad = 1 }
    exit bad
  }' "$1"
}

# Run FILE's commands in DIR; print "FILE:LINE: ..." and return 1 at the first
# that fails. NAME is how FILE is named in messages.
run_file() {
  file=$1 name=$2 dir=$3
  mkdir -p "$dir/build"
  ln -sf "$rtsim" "$dir/build/rtsim"
  ln -sfn "$src/configs" "$dir/configs"
  ln -sfn "$src/scenes" "$dir/scenes"
  [ -d "$scratch/results" ] || cp -R "$src/results" "$scratch/results"
  ln -sfn "$scratch/results" "$dir/results"
  list=$dir/.commands
  extract "$file" > "$list" || return 1
  count=0
  while IFS="$(printf '\t')" read -r line cmd; do
    count=$((count + 1))
    code=0
    (cd "$dir" && sh -c "$cmd") < /dev/null > "$dir/.out" 2>&1 || code=$?
    if [ "$code" != 0 ]; then
      echo "$name:$line: error: the command failed (exit $code): $cmd"
      sed 's/^/  | /' "$dir/.out" | tail -n 20
      return 1
    fi
  done < "$list"
  echo "$name: $count commands"
}

rm -rf "$scratch"
mkdir -p "$scratch"

# The check of the checker: the second command fails, at line 9.
page=$scratch/self-check.md
printf '%s\n' '# A page' '' '```sh' 'true \' '  && test 1 = 1' '```' '' '```sh' \
  'build/rtsim run --no-such-option' '```' '<!-- not run: it would fail -->' '```sh' 'false' '```' > "$page"
if out=$(run_file "$page" self-check.md "$scratch/self-check"); then
  echo "error: the runner passed a page whose command fails"; exit 1
fi
case $out in
  "self-check.md:9: error: the command failed (exit 2): build/rtsim run --no-such-option"*) ;;
  *) echo "error: the runner reported the wrong line or command: $out"; exit 1 ;;
esac

total=0
for f in "$src/README.md" "$src"/docs/*.md; do
  rel=${f#"$src/"}
  d=$scratch/$(echo "$rel" | tr '/.' '__')
  run_file "$f" "$rel" "$d" || exit 1
  total=$((total + $(wc -l < "$d/.commands")))
done
# The README is the door: a page a newcomer reads in minutes, not a manual.
lines=$(wc -l < "$src/README.md")
[ "$lines" -le 300 ] || { echo "error: README.md has $lines lines (at most 300: the rest goes to docs/)"; exit 1; }
# A page set with no command would pass without checking anything.
[ "$total" -ge 20 ] || { echo "error: only $total commands found in README.md and docs/"; exit 1; }
echo "doc commands: $total run"
