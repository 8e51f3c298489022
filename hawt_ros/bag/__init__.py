"""MCAP bags in the layout rosbag2 writes (pure Python; rclpy only for rclpy messages).

definitions (type names, ``.msg`` texts, type hashes) -> serialization (CDR, QoS) ->
writer (:class:`BagWriter` on ``mcap.writer.Writer``) / reader (:class:`BagReader`,
recovering) -> info (:func:`bag_info`) / recover (:func:`recover`: a finalized copy of a
crashed file).
"""
from .definitions import (DefinitionNotFound, message_class, message_definition,
                          normalize_type, type_hash, type_name_of)
from .info import bag_info, format_bag_info
from .reader import BagMessage, BagReader
from .recover import RecoveryReport, recover, recovered_path, unfinalized_recordings
from .serialization import qos_dict, serialize
from .writer import BagWriter, close_all_writers

__all__ = ["BagWriter", "BagReader", "BagMessage", "bag_info", "format_bag_info",
           "message_definition", "message_class", "normalize_type", "type_hash",
           "type_name_of", "serialize", "qos_dict", "close_all_writers", "DefinitionNotFound",
           "recover", "RecoveryReport", "recovered_path", "unfinalized_recordings"]
