"""Serial hardware-in-the-loop harness: run the generated controller on a board, prove on the wire
that it computes what the Python reference computes, and how long it takes.

Modules: ``schema`` (the protocol, defined once), ``crc32`` and ``framing``
(COBS frames with CRC-32), ``messages`` (payloads), ``codecgen`` (the
firmware's generated codec), ``link`` (pyserial), ``virtual`` (the host port
as a protocol program on a pseudo-terminal), ``boards``, ``session``
(handshake, pipelined replay, retries, resynchronisation, reset detection),
``states``, ``replay`` (mode ``replay``), ``closedloop`` (mode ``closed-loop``),
``onboard`` (mode ``onboard``), ``qemu`` (the emulated board), ``exchange_log``
(``--log``/``--check-log``), ``progress``, ``faults`` (a fault injector between
harness and board, for tests), ``cli`` (``mpcgen hil``).

hil imports codegen; codegen never imports hil (import-linter contract).
"""
