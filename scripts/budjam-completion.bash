# bash completion for budjam. Subcommands and options are read from the help text of the budjam
# being completed, so they are never out of date.
_budjam() {
  local cur=${COMP_WORDS[COMP_CWORD]} exe=${COMP_WORDS[0]}
  if ((COMP_CWORD == 1)); then
    COMPREPLY=($(compgen -W "$("$exe" --help 2>/dev/null |
      awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }') --help --version" -- "$cur"))
  elif [[ $cur == -* ]]; then
    COMPREPLY=($("$exe" "${COMP_WORDS[1]}" --help 2>/dev/null | grep -oE -- '(^|[ ,])--?[A-Za-z][-A-Za-z0-9]*' |
      tr -d ' ,' | sort -u | grep -- "^$cur"))
  else
    compopt -o default
    COMPREPLY=()
  fi
}
complete -F _budjam budjam
