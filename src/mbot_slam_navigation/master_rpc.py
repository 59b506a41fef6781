"""The ROS master's XML-RPC API with a timeout of its own.

xmlrpc waits for an answer as long as its socket does, which is for ever by default; a
process-wide socket timeout (socket.setdefaulttimeout) would reach rospy's own sockets too. This
proxy's connections alone give up after `timeout` s: socket.timeout, an OSError."""
import xmlrpc.client


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout: float):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host):
        conn = super().make_connection(host)
        conn.timeout = self.timeout  # read by http.client when it connects
        return conn


def master_proxy(uri: str, timeout: float) -> xmlrpc.client.ServerProxy:
    """A proxy of the master (or any XML-RPC server) at `uri` whose calls wait `timeout` s [wall] at most."""
    return xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout))
