"""Reading a qrtplan-view recording back with the `mcap` reader (the tests,
the renderer, tools/demo_can.sh): Foxglove's protobuf messages are decoded
with mcap-protobuf-support, the JSON channels with json."""

from __future__ import annotations

import json
from dataclasses import dataclass, field


@dataclass
class Recording:
    """topic -> schema name, and topic -> [(log_time_ns, message)]: a
    protobuf message, or a dict for a JSON channel."""
    schemas: dict[str, str] = field(default_factory=dict)
    encodings: dict[str, str] = field(default_factory=dict)
    messages: dict[str, list] = field(default_factory=dict)

    def count(self, topic):
        return len(self.messages.get(topic, []))

    def values(self, topic):
        return [m for _, m in self.messages.get(topic, [])]


def read(path) -> Recording:
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    rec = Recording()
    dec = DecoderFactory()
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        for ch in summary.channels.values():
            sch = summary.schemas.get(ch.schema_id)
            rec.schemas[ch.topic] = sch.name if sch else ""
            rec.encodings[ch.topic] = ch.message_encoding
            rec.messages[ch.topic] = []
        decoders = {}
        # in the order written (log_time order across channels is not
        # what the test checks; each channel's own order is)
        for sch, ch, msg in reader.iter_messages(log_time_order=False):
            if ch.message_encoding == "json":
                value = json.loads(msg.data)
            else:
                d = decoders.get(ch.id)
                if d is None:
                    d = decoders[ch.id] = dec.decoder_for(
                        ch.message_encoding, sch)
                value = d(msg.data)
            rec.messages[ch.topic].append((msg.log_time, value))
    return rec
