"""Whether SocketCAN can be used here (stdlib only: cheap to import in the VM)."""
from __future__ import annotations

import socket


def vcan_problem(channel: str = "vcan0") -> str | None:
    """Why SocketCAN on `channel` cannot be used here, or None."""
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except (OSError, AttributeError) as e:
        return f"no SocketCAN in this kernel ({e}); run under tools/with-vcan"
    try:
        s.bind((channel,))
    except OSError as e:
        return f"no CAN interface {channel} ({e}); run under tools/with-vcan"
    finally:
        s.close()
    return None
