# track_lib.sh — helpers the `eventlfm track` shell tests share (sourced).

# key FILE KEY: the number after "KEY": in a JSON file (summary.json, or
# `eventlfm score --json` output); empty when absent.
key() {
  tr ',{}' '\n\n\n' < "$1" | sed -n "s/^[[:space:]]*\"$2\":[[:space:]]*//p" | head -1
}

# below A F B: true when A < F x B (floating point, by awk).
below() {
  awk -v a="$1" -v f="$2" -v b="$3" 'BEGIN { exit !(a < f * b) }'
}
