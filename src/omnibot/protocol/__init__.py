"""The motor-controller protocol: codes, messages, the text codec and the binary codec (docs/protocol.md).

Pure codecs: no I/O, no threads. ``codes``, ``crc``, ``frame`` and ``arq`` run under MicroPython too
(the firmware imports them), so this package module imports nothing; import the submodules::

    from omnibot.protocol import messages, text, binary
"""

__all__ = ["arq", "binary", "codes", "frame", "linecheck", "messages", "text", "units"]
