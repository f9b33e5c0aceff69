"""Ports of user classes related by inheritance (BT.CPP 4.10's polymorphic ports): an input
port may read an entry of a base or derived class; the value's class is checked on each read."""

from __future__ import annotations

import pytest

from bt_runtime import (
    BehaviorTreeFactory,
    BTRuntimeError,
    NodeStatus,
    SyncActionNode,
    XMLLoadError,
    bidirectional_port,
    input_port,
    output_port,
)
from tests.engine.helpers import doc


class Vehicle:
    label = "vehicle"


class Truck(Vehicle):
    label = "truck"


class Tanker(Truck):
    label = "tanker"


class Boat:
    label = "boat"


def maker(cls, declared):
    class Make(SyncActionNode):
        @staticmethod
        def provided_ports():
            return [output_port("out", declared)]

        def tick(self):
            self.set_output("out", cls())
            return NodeStatus.SUCCESS
    return Make


def reader(declared, seen):
    class Read(SyncActionNode):
        @staticmethod
        def provided_ports():
            return [input_port("item", declared)]

        def tick(self):
            try:
                seen.append(self.get_input("item").label)
            except BTRuntimeError:
                return NodeStatus.FAILURE
            return NodeStatus.SUCCESS
    return Read


class Update(SyncActionNode):
    @staticmethod
    def provided_ports():
        return [bidirectional_port("item", Vehicle)]

    def tick(self):
        return NodeStatus.SUCCESS


@pytest.fixture
def setup():
    seen: list[str] = []
    factory = BehaviorTreeFactory()
    factory.register_node_type(maker(Truck, Truck), "MakeTruck")
    factory.register_node_type(maker(Tanker, Tanker), "MakeTanker")
    factory.register_node_type(maker(Vehicle, Vehicle), "MakeVehicle")
    factory.register_node_type(maker(Truck, Vehicle), "MakeTruckAsVehicle")
    factory.register_node_type(reader(Vehicle, seen), "ReadVehicle")
    factory.register_node_type(reader(Truck, seen), "ReadTruck")
    factory.register_node_type(reader(Boat, seen), "ReadBoat")
    factory.register_node_type(Update)
    return factory, seen


def run(factory, body):
    return factory.create_tree_from_text(doc(f"<Sequence>{body}</Sequence>")).tick_while_running()


def test_upcast_through_the_hierarchy(setup):
    factory, seen = setup
    assert run(factory, '<MakeTanker out="{v}"/><ReadTruck item="{v}"/><ReadVehicle item="{v}"/>') is NodeStatus.SUCCESS
    assert seen == ["tanker", "tanker"]


def test_downcast_checked_when_read(setup):
    factory, seen = setup
    assert run(factory, '<MakeTruckAsVehicle out="{v}"/><ReadTruck item="{v}"/>') is NodeStatus.SUCCESS
    assert run(factory, '<MakeVehicle out="{v}"/><ReadTruck item="{v}"/>') is NodeStatus.FAILURE
    assert seen == ["truck"]


def test_unrelated_classes_are_refused_at_build(setup):
    factory, _ = setup
    with pytest.raises(XMLLoadError, match=r"initially created with type \[Truck\] and, later type \[Boat\]"):
        run(factory, '<MakeTruck out="{v}"/><ReadBoat item="{v}"/>')


def test_inout_port_needs_the_same_class(setup):
    factory, _ = setup
    with pytest.raises(XMLLoadError, match="initially created with type"):
        run(factory, '<MakeTruck out="{v}"/><Update item="{v}"/>')
