"""``--foxglove [PORT]``: the recorder's messages served live through the Foxglove SDK's WebSocket
server (``foxglove-sdk``), the same channels and ROS 2 schemas as the log file, so Foxglove shows a
running robot as it shows a recorded one. The server binds 127.0.0.1 only (there is no token yet, so
no other address is offered)."""

from __future__ import annotations

from typing import Any

from omnibot.errors import ConfigError
from omnibot.logs import schemas

DEFAULT_PORT = 8765
HOST = "127.0.0.1"


class FoxgloveLive:
    """A Foxglove WebSocket server on 127.0.0.1:``port`` (0: a free port, see :attr:`port`); call it as
    a recorder mirror, ``live(topic, typename, cdr_bytes, ns)``; :meth:`close` stops it."""

    def __init__(self, port: int = DEFAULT_PORT, *, name: str = "omnibot") -> None:
        import foxglove

        self._foxglove = foxglove
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name=name, host=HOST, port=port, context=self._context)
        except Exception as exc:  # the SDK raises its own error for a port in use
            raise ConfigError(f"cannot serve Foxglove on {HOST}:{port}: {exc}", key="--foxglove") from None
        self.port: int = self._server.port
        self._channels: dict[str, Any] = {}

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """Publish one recorded message (CDR ``data`` of ``typename``) on ``topic``, its channel made
        on first use."""
        channel = self._channels.get(topic)
        if channel is None:
            schema = self._foxglove.Schema(
                name=typename, encoding="ros2msg", data=schemas.schema_text(typename).encode("utf-8")
            )
            channel = self._foxglove.Channel(
                topic, schema=schema, message_encoding="cdr", context=self._context
            )
            self._channels[topic] = channel
        channel.log(data, log_time=ns)

    def close(self) -> None:
        """Close every channel and stop the server."""
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
        self._server.stop()
