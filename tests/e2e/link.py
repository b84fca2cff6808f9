"""A TCP proxy between the browser and the server that a test can break, as a
field Wi-Fi link breaks: ``cut()`` kills every connection and refuses new ones,
``stall()`` keeps them open but lets no byte through (a half-open link, which a
browser cannot tell from a slow one), ``restore()`` lets traffic flow again."""

import socket
import threading


class Link:
    def __init__(self, server):
        self.target = ("127.0.0.1", server.port)
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"http://127.0.0.1:{self.listener.getsockname()[1]}"
        self.up = True
        self.flowing = threading.Event()
        self.flowing.set()
        self.lock = threading.Lock()
        self.sockets: set[socket.socket] = set()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self):
        while True:
            try:
                client, _ = self.listener.accept()
            except OSError:
                return  # closed
            if not self.up:
                client.close()
                continue
            try:
                upstream = socket.create_connection(self.target)
            except OSError:
                client.close()
                continue
            with self.lock:
                self.sockets.update((client, upstream))
            for source, sink in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pump, args=(source, sink), daemon=True).start()

    def _pump(self, source, sink):
        try:
            while data := source.recv(65536):
                self.flowing.wait()
                sink.sendall(data)
        except OSError:
            pass
        finally:
            self._drop(source, sink)

    def _drop(self, *sockets):
        with self.lock:
            for s in sockets:
                self.sockets.discard(s)
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
                s.close()

    def cut(self):
        self.up = False
        with self.lock:
            alive = list(self.sockets)
        self._drop(*alive)

    def stall(self):
        self.flowing.clear()

    def restore(self):
        self.up = True
        self.flowing.set()

    def close(self):
        self.restore()
        self.listener.close()
        self.cut()
