"""Road-network readers: the real Haikou networks and every bad-input case on a fake folder."""

from __future__ import annotations

import gzip

import pytest

from rpbench.data import read_haikou_network, read_predecessor_network
from rpbench.exceptions import DataError, DataNotFoundError
from rpbench.network import RoadNetwork


def test_haikou_network_has_both_directions_of_every_link(data_dir):
    tables = read_haikou_network(data_dir)
    assert len(tables.node_id) == 3901
    assert len(tables.arc_from) == 2 * 5458
    net = RoadNetwork.from_tables(tables)  # checks strong connectivity
    assert net.n_nodes == 3901 and net.n_arcs == 10916
    assert (net.arc_length_m > 0).all()


def test_predecessor_network(data_dir):
    net = RoadNetwork.from_tables(read_predecessor_network(data_dir))
    assert net.n_nodes == 724 and net.n_arcs == 1955


def test_fake_network_reads(fake_data):
    net = RoadNetwork.from_tables(read_haikou_network(fake_data))
    assert net.n_nodes == 9 and net.n_arcs == 24


def _rewrite_links(fake_data, edit):
    path = fake_data / "network" / "link.csv.gz"
    with gzip.open(path, "rt") as fh:
        lines = fh.read().splitlines()
    with gzip.open(path, "wt") as fh:
        fh.write("\n".join(edit(lines)) + "\n")


def test_missing_node_file(fake_data):
    (fake_data / "network" / "node.csv").unlink()
    with pytest.raises(DataNotFoundError, match="node.csv"):
        read_haikou_network(fake_data)


def test_missing_column(fake_data):
    _rewrite_links(fake_data, lambda ls: [ls[0].replace("length", "len")] + ls[1:])
    with pytest.raises(DataError, match="lacks column.*'length'"):
        read_haikou_network(fake_data)


def test_non_numeric_value(fake_data):
    _rewrite_links(fake_data, lambda ls: ls[:2] + [ls[2].rsplit(",", 1)[0] + ",abc"] + ls[3:])
    with pytest.raises(DataError, match=r"column 'length', data row 2: value 'abc' is not a finite number"):
        read_haikou_network(fake_data)


def test_unknown_node_in_links(fake_data):
    _rewrite_links(fake_data, lambda ls: ls + ['99,0,77,5,"LINESTRING (0 0, 1 1)",500.0'])
    with pytest.raises(DataError, match="node id 77 is not in the node file"):
        read_haikou_network(fake_data)


def test_network_not_strongly_connected(fake_data):
    # Drop every link touching node 8: it becomes unreachable.
    _rewrite_links(fake_data, lambda ls: [ls[0]] + [line for line in ls[1:] if ",8," not in line])
    with pytest.raises(DataError, match="not strongly connected"):
        RoadNetwork.from_tables(read_haikou_network(fake_data))
