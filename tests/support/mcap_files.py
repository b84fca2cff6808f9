"""Reading snapshot MCAP files back the way any standard reader does."""

from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def read_mcap(path: Path) -> dict:
    """{"profile", "schemas": {type: text}, "messages": [(topic, log_time ns, decoded)]}."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        messages, schemas = [], {}
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            schemas[schema.name] = schema.data.decode()
            assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
            messages.append((channel.topic, message.log_time, decoded))
    return {"profile": header.profile, "schemas": schemas, "messages": messages}


def write_fixes(path: Path, latitudes) -> dict:
    """A small real snapshot: NavSatFix messages on /gps_fix; its topics summary."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import NavSatFix

    from rosbridge_app.collector.mcap_files import MessageDefinitions, write_mcap

    messages = [
        (i, "/gps_fix", serialize_message(NavSatFix(latitude=lat)))
        for i, lat in enumerate(latitudes)
    ]
    types = {"/gps_fix": "sensor_msgs/msg/NavSatFix"}
    return write_mcap(path, messages, types, MessageDefinitions())
