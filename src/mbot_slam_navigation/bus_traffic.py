"""What crosses one host's network link, per topic: the bytes of every TCPROS connection between a
node on that host and a node elsewhere, from the nodes' own counters (the slave API's getBusInfo
and getBusStats, which roscpp and rospy both serve).

    python3 -m mbot_slam_navigation.bus_traffic --master http://10.211.0.1:11311 --host 10.211.0.11 [--by-peer]

prints a JSON object {topic: bytes} (message bytes as the nodes count them, since each node
started; TCP/IP headers not included), or with --by-peer {peer node: {topic: bytes}}, the peer
being the node on the other host. Run it where the master and the host's nodes can be reached.
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
    out: Dict[str, int] = {}
    for topics in host_traffic_by_peer(master_uri, host_ip, timeout).values():
        for topic, n in topics.items():
            out[topic] = out.get(topic, 0) + n
    return out


def host_traffic_by_peer(master_uri: str, host_ip: str, timeout: float = 5.0) -> Dict[str, Dict[str, int]]:
    """{peer node: {topic: bytes}} over the connections between nodes at `host_ip` and nodes at
    other addresses ('?' for a peer the master no longer knows)."""
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
    node_of_uri = {u.rstrip('/'): n for n, u in uris.items()}
    out: Dict[str, Dict[str, int]] = {}
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
        # connection [id, bytes, ...]. A connection's destination is the peer's URI or its name.
        if len(stats) == 3 and isinstance(stats[0], int):
            stats = stats[2]
        pub_stats, sub_stats = stats[0], stats[1]
        peers = {}  # connection id -> (the peer node, its address)
        for conn in info:
            conn_id, dest = conn[0], str(conn[1])
            peer = node_of_uri.get(dest.rstrip('/'), dest if dest in hosts else '?')
            peers[conn_id] = (peer, hosts.get(peer) or (_host_of(dest) if '://' in dest else ''))
        for entry in list(pub_stats) + list(sub_stats):
            topic, conns = entry[0], entry[-1]
            for c in conns:
                peer, address = peers.get(c[0], ('?', ''))
                if address and address != host_ip:
                    by_topic = out.setdefault(peer, {})
                    by_topic[topic] = by_topic.get(topic, 0) + int(c[1])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--master', required=True)
    ap.add_argument('--host', required=True, help="the host's address")
    ap.add_argument('--by-peer', action='store_true', help='{peer node: {topic: bytes}}')
    a = ap.parse_args(argv)
    try:
        print(json.dumps((host_traffic_by_peer if a.by_peer else host_traffic)(a.master, a.host)))
    except (OSError, RuntimeError) as e:
        print('bus_traffic: %s' % e, file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main())
