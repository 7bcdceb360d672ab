# bash completion for budjam. Subcommands, options and the values of an option that takes one of
# a set ({a,b,c} in its help) are read from the help text of the budjam being completed, so they
# are never out of date.
_budjam() {
  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD - 1]} exe=${COMP_WORDS[0]} choices
  if ((COMP_CWORD == 1)); then
    COMPREPLY=($(compgen -W "$("$exe" --help 2>/dev/null |
      awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }') --help --version" -- "$cur"))
  elif [[ $cur == -* ]]; then
    COMPREPLY=($("$exe" "${COMP_WORDS[1]}" --help 2>/dev/null | grep -oE -- '(^|[ ,])--?[A-Za-z][-A-Za-z0-9]*' |
      tr -d ' ,' | sort -u | grep -- "^$cur"))
  elif [[ $prev == -* ]] && choices=$("$exe" "${COMP_WORDS[1]}" --help 2>/dev/null |
    sed -n "s/^ *\(-[A-Za-z], *\)\{0,1\}$prev [^{ ]*{\([^}]*\)}.*/\2/p") && [[ -n $choices ]]; then
    COMPREPLY=($(compgen -W "${choices//,/ }" -- "$cur"))
  else
    compopt -o default
    COMPREPLY=()
  fi
}
complete -F _budjam budjam
