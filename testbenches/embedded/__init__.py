"""The C twin on a microcontroller: `make embedded` (testbenches.embedded.build)."""
