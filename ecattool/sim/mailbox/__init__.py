"""Mailbox protocols of a virtual EtherCAT slave: CoE (SDO, SDO information, Emergency) and FoE, over the
6-byte mailbox header. A :class:`MailboxServer` turns the frames a master writes to SM0 into calls of the
drive's public API and queues the replies for SM1.

    from ecattool.sim import Drive
    from ecattool.sim.mailbox import MailboxServer
    mbx = MailboxServer(Drive.from_profile("hdt"), out_size=128, in_size=128)
    mbx.handle(request)        # bytes the master wrote to SM0
    reply = mbx.pending()      # bytes for SM1, or None
"""

from ecattool.sim.mailbox.header import MailboxError, MailboxHeader, MailboxType
from ecattool.sim.mailbox.server import MailboxServer

__all__ = ["MailboxError", "MailboxHeader", "MailboxServer", "MailboxType"]
