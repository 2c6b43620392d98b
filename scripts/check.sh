#!/bin/sh
# What must pass before a commit: formatting, lints and the whole test suite.
set -eu
cd "$(dirname "$0")/.."
cargo fmt --all -- --check
cargo clippy --all-targets -- -D warnings
cargo test --release
