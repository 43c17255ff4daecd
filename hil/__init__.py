"""Serial hardware-in-the-loop harness (the HIL protocol): planned in a later issue; nothing here yet."""
