# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by tools/sanitize (and its test). targets_of BUILD_DIR [CTEST_ARGS...]: the build
# targets the tests ctest selects with CTEST_ARGS need, one per line, or "all".
#
# The build targets behind the selected tests: each test's executable in the build tree
# (plugins it loads are dependencies of that target). A test labelled "source" reads only the
# source tree (the function-length checks) and needs nothing built. Any other test run through
# a script (soak, security, service) does not say what it needs, so its presence means "build
# everything".
targets_of() {
  local build=$1; shift
  # ctest -N -V prints, per test, its command (or, when the executable is not built yet, one it
  # "could not find"), then its labels, then "Test #N: name".
  ctest --test-dir "$build" -N -V "$@" 2>&1 |
    awk -v build="$build" '
      /^[0-9]+: Test command: / {
        # Blank (two spaces, then the arguments) when the executable is not built yet.
        rest = $0; sub(/^[0-9]+: Test command: /, "", rest)
        if (rest != "" && substr(rest, 1, 1) != " ") { split(rest, words, " "); command = words[1] }
        next
      }
      /^Could not find executable / { command = $5; next }
      /^Labels:/ { labels = " " substr($0, 8) " "; next }
      /^ *Test +#[0-9]+:/ {
        if (labels !~ / source /) {
          if (index(command, build "/tests/") == 1 || index(command, build "/bin/") == 1) {
            n = split(command, parts, "/"); print parts[n]
          } else {
            print "all"
          }
        }
        command = ""; labels = ""
      }' | sort -u
}
