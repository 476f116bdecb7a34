"""LCM's Python calls used by publish_keyframes.py, over the C library through ctypes.

Debian 12 packages liblcm but no Python module; this gives the same four calls (LCM(url),
publish, subscribe, handle_timeout) on top of liblcm.so.1, so the example runs wherever the
node does. With LCM's own module installed (`import lcm`) the example uses that instead.
"""
import ctypes
import ctypes.util


class _RecvBuf(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("data_size", ctypes.c_uint32),
                ("recv_utime", ctypes.c_int64), ("lcm", ctypes.c_void_p)]


_HANDLER = ctypes.CFUNCTYPE(None, ctypes.POINTER(_RecvBuf), ctypes.c_char_p, ctypes.c_void_p)


def _load():
    name = ctypes.util.find_library("lcm") or "liblcm.so.1"
    lib = ctypes.CDLL(name)  # OSError, naming the library, when liblcm is not installed
    lib.lcm_create.restype = ctypes.c_void_p
    lib.lcm_create.argtypes = [ctypes.c_char_p]
    lib.lcm_publish.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p, ctypes.c_uint]
    lib.lcm_subscribe.restype = ctypes.c_void_p
    lib.lcm_subscribe.argtypes = [ctypes.c_void_p, ctypes.c_char_p, _HANDLER, ctypes.c_void_p]
    lib.lcm_handle_timeout.argtypes = [ctypes.c_void_p, ctypes.c_int]
    return lib


class LCM:
    def __init__(self, url=""):
        self._lib = _load()
        self._lcm = self._lib.lcm_create(url.encode())
        if not self._lcm:
            raise IOError(f"lcm_create failed for {url!r}")
        self._handlers = []  # the C side keeps only pointers: hold the callbacks here

    def publish(self, channel, data):
        if self._lib.lcm_publish(self._lcm, channel.encode(), data, len(data)) != 0:
            raise IOError(f"lcm_publish failed on {channel}")

    def subscribe(self, channel, handler):
        def on_message(rbuf, chan, _user):
            handler(chan.decode(), ctypes.string_at(rbuf.contents.data, rbuf.contents.data_size))
        callback = _HANDLER(on_message)
        self._handlers.append(callback)
        if not self._lib.lcm_subscribe(self._lcm, channel.encode(), callback, None):
            raise IOError(f"lcm_subscribe failed on {channel}")

    def handle_timeout(self, timeout_ms):
        return self._lib.lcm_handle_timeout(self._lcm, int(timeout_ms))
