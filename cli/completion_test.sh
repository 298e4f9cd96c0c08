#!/usr/bin/env bash
# `hmc completion bash|zsh`: the bash script completes as a user's TAB would (subcommands,
# nested subcommands, options after '-', an option's value skipped); the zsh script parses.
# Usage: completion_test.sh HMC_BINARY
set -uo pipefail
hmc=$1
failures=0
script=$(mktemp)
trap 'rm -f "$script"' EXIT

"$hmc" completion bash >"$script" || { echo "FAIL: hmc completion bash exited $?"; exit 1; }

# complete WANT WORDS...: TAB after WORDS (the last one is the word under the cursor).
complete_as() {
  local want=$1
  shift
  local got
  got=$(bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _hmc; echo "${COMPREPLY[*]}"' \
        _ "$script" "$@")
  if [[ $got != "$want" ]]; then
    failures=$((failures + 1))
    printf 'FAIL: completing "%s" gave "%s", want "%s"\n' "$*" "$got" "$want"
  fi
}

complete_as "move monitor" hmc mo
complete_as "encode decode check" hmc frame ""
complete_as "move monitor" hmc --port /dev/ttyUSB0 mo       # --port's value is skipped
complete_as "--method" hmc flash --me
complete_as "--json" hmc status --js                        # hmc's own options after a subcommand
complete_as "" hmc --port mo                                # on --port's value: file names

if "$hmc" completion fish >/dev/null 2>&1; then
  failures=$((failures + 1))
  echo "FAIL: hmc completion fish was accepted"
fi
if command -v zsh >/dev/null; then
  "$hmc" completion zsh | zsh -n || { failures=$((failures + 1)); echo "FAIL: the zsh script does not parse"; }
else
  echo "note: zsh is not installed; the zsh script's syntax was not checked"
fi

[[ $failures -eq 0 ]] && echo "completion_test: ok" || exit 1
