"""A message's fields from a YAML string, as ros2cli fills them.

As for `ros2 topic pub`, `ros2 service call` and `ros2 action send_goal` (rosidl_runtime_py.set_message_fields, which is
on no registry here).

Each key names a field; its value is converted to the type the field holds (an int to a float64 field's float, a
list to an array.array of the field's type code), a mapping fills a nested message, and a list of mappings fills a
sequence of messages. An unknown field is an AttributeError, a value of the wrong kind a TypeError or ValueError, as
ros2cli reports them. Tests use it to send what an operator would type.
"""
from __future__ import annotations

import array
import importlib
from typing import Any

import yaml


def message_from_yaml(message_type: Any, text: str) -> Any:
    """A message of message_type with the fields of the YAML mapping text set, the others at their defaults."""
    message = message_type()
    values = yaml.safe_load(text) or {}
    if not isinstance(values, dict):
        raise TypeError(f"a message's fields are a YAML mapping, got {type(values).__name__}")
    set_message_fields(message, values)
    return message


def set_message_fields(message: Any, values: dict) -> None:
    """Set message's fields from values (field name -> value), converting each as ros2cli does."""
    slot_types = dict(zip(message.__slots__, message.SLOT_TYPES))
    for name, value in values.items():
        if f"_{name}" not in slot_types:
            raise AttributeError(f"{type(message).__name__} has no field '{name}'")
        current = getattr(message, name)
        field_type = type(current)
        if field_type is array.array:
            converted: Any = array.array(current.typecode, value)
        elif type(value) is field_type:
            converted = value
        else:
            try:
                converted = field_type(value)
            except TypeError:
                converted = field_type()
                set_message_fields(converted, value)
        element_type = _message_element_type(slot_types[f"_{name}"])
        if element_type is not None:
            elements = []
            for element_values in converted:
                element = element_type()
                set_message_fields(element, element_values)
                elements.append(element)
            converted = elements
        setattr(message, name, converted)


def _message_element_type(slot_type: Any) -> Any:
    """The message class of a sequence of messages' elements; None for any other field."""
    # rosidl_parser's AbstractNestedType has a value_type; a NamespacedType (a message) has namespaces
    namespaces = getattr(getattr(slot_type, "value_type", None), "namespaces", None)
    if namespaces is None:
        return None
    return getattr(importlib.import_module(".".join(namespaces)), slot_type.value_type.name)
