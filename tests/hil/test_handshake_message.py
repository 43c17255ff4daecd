"""A board that does not answer HELLO: the message says whether anything arrived (garbage usually means
a wrong baud rate) or nothing at all."""
from __future__ import annotations

import pytest
from hil_support import example

from hil.schema import Schema
from hil.session import BoardSilent, Session


class _Talker:
    """A link whose far end answers every write with ``reply`` (nothing or garbage)."""

    octets_out = octets_in = 0

    def __init__(self, reply: bytes) -> None:
        self.reply, self.pending = reply, b""

    def write(self, data: bytes) -> None:
        self.pending += self.reply

    def read_waiting(self) -> bytes:
        data, self.pending = self.pending, b""
        return data

    def wait(self, timeout_s: float) -> None:
        pass

    def close(self) -> None:
        pass


@pytest.mark.parametrize("reply,fragment", [
    (b"\x00\x13\x37\xff\xfe\x81\x00", "undecodable chunk(s) arrived"),
    (b"", "nothing at all arrived"),
])
def test_no_info_says_what_arrived(reply, fragment):
    m, _t = example("spmsm", "conventional")
    session = Session(_Talker(reply), Schema.of(m), timeout_s=0.02, retries=0)
    with pytest.raises(BoardSilent) as err:
        session.handshake(attempts=2)
    assert fragment in str(err.value) and "no INFO after 2 HELLOs" in str(err.value)
