"""Whether nodes on other hosts can connect back to this one: ROS 1's classic misconfiguration is a
host that advertises an address its peers cannot reach (ROS_IP unset on a machine whose name
resolves to 127.0.1.1, or ROS_IP set to an address of another machine). Subscriptions then connect
to nothing and topics are silently missing; this says what to set instead."""
import socket
from urllib.parse import urlparse


def _is_loopback(ip: str) -> bool:
    return ip.startswith('127.') or ip == '::1'


def address_problem(master_uri: str, own_uri: str) -> str:
    """Why nodes on the master's network may not reach a node whose XML-RPC URI is `own_uri`, or ''."""
    master_host, own_host = urlparse(master_uri).hostname or '', urlparse(own_uri).hostname or ''
    try:
        master_ip = socket.gethostbyname(master_host)
    except OSError:
        return ''  # the master's own name: rospy has said so already
    try:
        own_ip = socket.gethostbyname(own_host)
    except OSError as e:
        return ('this node advertises the name %s, which does not resolve here (%s); set ROS_IP to this host\'s '
                'address on the network of the master (%s)' % (own_host, e.strerror or e, master_host))
    if _is_loopback(master_ip):
        return ''  # one machine: loopback is right
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.connect((master_ip, 11311))  # no packet: picks the route and so the local address
            route_ip = s.getsockname()[0]
    except OSError:
        route_ip = ''
    if _is_loopback(own_ip):
        return ('this node advertises %s (%s), a loopback address, but the master is at %s on another host: nodes '
                'there cannot connect back and its topics will be missing; set ROS_IP=%s (this host\'s address '
                'towards the master) or ROS_HOSTNAME to a name the other hosts resolve'
                % (own_host, own_ip, master_host, route_ip or '<this host\'s address>'))
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.bind((own_ip, 0))
    except OSError:
        return ('this node advertises %s (%s), which is not an address of this host: nodes elsewhere will connect '
                'to another machine; set ROS_IP=%s' % (own_host, own_ip, route_ip or '<this host\'s address>'))
    return ''
