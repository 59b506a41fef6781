"""What crosses one host's network link, per topic: the bytes of every TCPROS connection between a
node on that host and a node elsewhere, from the nodes' own counters (the slave API's getBusInfo
and getBusStats, which roscpp and rospy both serve).

    python3 -m mbot_slam_navigation.bus_traffic --master http://10.211.0.1:11311 --host 10.211.0.11

prints a JSON object {topic: bytes} (message bytes as the nodes count them, since each node
started; TCP/IP headers not included). Run it where the master and the host's nodes can be reached.
"""
import argparse
import json
import socket
import sys
from typing import Dict
from urllib.parse import urlparse

from mbot_slam_navigation.master_rpc import master_proxy

CALLER = '/bus_traffic'


def _host_of(uri: str) -> str:
    host = urlparse(uri).hostname or ''
    try:
        return socket.gethostbyname(host)
    except OSError:
        return host


def host_traffic(master_uri: str, host_ip: str, timeout: float = 5.0) -> Dict[str, int]:
    """{topic: bytes} over the connections between nodes at `host_ip` and nodes at other addresses."""
    master = master_proxy(master_uri, timeout)
    code, _, state = master.getSystemState(CALLER)
    if code != 1:
        raise RuntimeError('the master at %s did not give its state' % master_uri)
    nodes = sorted({n for kind in state for _, names in kind for n in names})
    uris = {}
    for n in nodes:
        code, _, uri = master.lookupNode(CALLER, n)
        if code == 1:
            uris[n] = uri
    hosts = {n: _host_of(u) for n, u in uris.items()}
    by_uri_host = {u.rstrip('/'): hosts[n] for n, u in uris.items()}
    out: Dict[str, int] = {}
    for n, uri in uris.items():
        if hosts[n] != host_ip:
            continue
        node = master_proxy(uri, timeout)
        try:
            _, _, info = node.getBusInfo(CALLER)
            stats = node.getBusStats(CALLER)
        except (OSError, ValueError, TypeError):
            continue  # the node ended, or does not serve the stats
        # rospy answers [code, text, stats]; roscpp the stats alone. Publications are
        # [topic, (rospy: data sent,) connections], subscriptions [topic, connections]; each
        # connection [id, bytes, ...].
        if len(stats) == 3 and isinstance(stats[0], int):
            stats = stats[2]
        pub_stats, sub_stats = stats[0], stats[1]
        # connection id -> (topic, the peer's address)
        peers = {}
        for conn in info:
            conn_id, dest, topic = conn[0], str(conn[1]), conn[4]
            peer = by_uri_host.get(dest.rstrip('/')) or hosts.get(dest) or (_host_of(dest) if '://' in dest else '')
            peers[conn_id] = (topic, peer)
        for entry in list(pub_stats) + list(sub_stats):
            topic, conns = entry[0], entry[-1]
            for c in conns:
                _, peer = peers.get(c[0], (topic, ''))
                if peer and peer != host_ip:
                    out[topic] = out.get(topic, 0) + int(c[1])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--master', required=True)
    ap.add_argument('--host', required=True, help="the host's address")
    a = ap.parse_args(argv)
    try:
        print(json.dumps(host_traffic(a.master, a.host)))
    except (OSError, RuntimeError) as e:
        print('bus_traffic: %s' % e, file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main())
