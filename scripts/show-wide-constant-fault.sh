#!/usr/bin/env bash
# The script moved to tools/wide_constant_fault/ with the reproducer it compiles; this path
# still runs it. Usage: scripts/show-wide-constant-fault.sh [CXX]
exec bash "$(dirname "$0")/../tools/wide_constant_fault/show-wide-constant-fault.sh" "$@"
