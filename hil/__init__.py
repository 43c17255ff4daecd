"""Serial hardware-in-the-loop harness (shared/spec/hil.md): planned in a later issue; nothing here yet."""
