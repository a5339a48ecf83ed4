"""Origin signatures: an AON payload travels with its author's signature, so that no
member can put words in another's mouth, even inside its own publications.

The access-control list binds a publication to its publisher's key; AON's members
re-publish each other's payloads (that is how a message reaches everyone), so a
publication can carry payloads of other origins, and the ACL cannot tell a faithful
copy from a forgery. In a live team with certificates, the member that originates an
AON entry signs it with its certificate's key (ECDSA P-256, the key of its TLS
identity), and every copy carries that signature — in the Zenoh attachment, not in the
message, so simulated results and message sizes do not change; a receiving bus verifies
it against the certificate of the member that may speak for the origin (the grants of
the team's ACL: the assigner's entries by the robot that hosts it) and drops an entry
whose signature is missing or wrong (counted: ``unsigned_entry``). The signatures a
process has verified (or made) are remembered (at most :data:`MAX_REMEMBERED`): they
go with the copies it publishes, and an entry heard again with the same signature and
payload is not verified again, nor is its own entry signed again when AON re-sends it.

Without certificates (``--insecure``) nothing is signed: anyone could forge anything
anyway.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any

import msgspec
from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec

from mrcomm.messaging.messages import (
    TOPIC_AON,
    TOPIC_COMMAND,
    TOPIC_RELAYED,
    TOPIC_TASK_STATUS,
    AonEntry,
    AonMsg,
    Message,
    RelayedMsg,
    TaskStatus,
    decode,
    encode,
)
from mrcomm.net.zenoh_config import ZenohOptions

#: The topics whose entries are signed by their origin.
SIGNED_TOPICS = frozenset({TOPIC_AON, TOPIC_COMMAND})
#: With relaying on, task statuses are signed too (for the copies relaying robots pass
#: on), and relayed copies carry their origin's signatures.
RELAY_SIGNED_TOPICS = frozenset({TOPIC_TASK_STATUS, TOPIC_RELAYED})
#: Verified signatures remembered to go with copies this process publishes.
MAX_REMEMBERED = 8192
_DOMAIN = b"mrcomm-origin-v1\0"

#: (topic, origin, incarnation, sequence number): one AON message.
Key = tuple[str, str, int, int]
_encode_key = msgspec.msgpack.Encoder().encode


def signed_bytes(topic: str, origin: str, incarnation: int, seq: int, payload: Any) -> bytes:
    """What the origin signs: the message's identity and its payload."""
    return _DOMAIN + _encode_key((topic, origin, incarnation, seq)) + encode(payload)


def _of(entry: AonEntry) -> tuple[str, int, int, Any]:
    return entry.sender, entry.incarnation, entry.seq, entry.payload


def _of_status(status: TaskStatus) -> tuple[str, int, int, Any]:
    return status.sender, status.incarnation, status.seq, status


class OriginSigner:
    """One process's signing key and the team's verifying keys (see the module
    docstring)."""

    def __init__(
        self,
        key: ec.EllipticCurvePrivateKey,
        speakers: Mapping[str, ec.EllipticCurvePublicKey] | None,
    ) -> None:
        """``speakers``: origin (a key chunk) -> the public key of the certificate that
        may speak for it (None: not every member's certificate is at hand, so this
        process signs its own entries but verifies none)."""
        self._key = key
        self.verifies = speakers is not None
        self._speakers = dict(speakers or {})
        #: (signature, the bytes it signs) of the messages verified or made here.
        self._remembered: OrderedDict[Key, tuple[bytes, bytes]] = OrderedDict()

    @classmethod
    def from_options(cls, options: ZenohOptions) -> OriginSigner | None:
        """The signer of a process with a team's certificates: its own key, and each
        member's certificate from the directory its own is in (a team directory holds
        them all; without one of them, this process verifies nothing). None without
        TLS and access control, or with a key of another kind."""
        if options.tls is None or options.acl_grants is None:
            return None
        try:
            private = serialization.load_pem_private_key(options.tls.key.read_bytes(), None)
        except (OSError, ValueError):
            return None
        if not isinstance(private, ec.EllipticCurvePrivateKey):
            return None
        return cls(private, _speakers(Path(options.tls.cert).parent, options.acl_grants))

    def sign(self, topic: str, entry: AonEntry | TaskStatus) -> bytes:
        """Sign an AON entry (or a task status) this process originates, and remember
        the signature for copies (an origin never reuses a message's identity: the
        remembered one is given again when AON re-sends it)."""
        origin, inc, seq, payload = (
            _of_status(entry) if isinstance(entry, TaskStatus) else _of(entry)
        )
        key = (topic, origin, inc, seq)
        known = self._remembered.get(key)
        if known is not None:
            return known[0]
        data = signed_bytes(topic, origin, inc, seq, payload)
        signature = self._key.sign(data, ec.ECDSA(hashes.SHA256()))
        self._remember(key, signature, data)
        return signature

    def verify(self, topic: str, entry: AonEntry | TaskStatus, signature: bytes | None) -> bool:
        """Whether ``signature`` is the origin's (then it is remembered)."""
        origin, inc, seq, payload = (
            _of_status(entry) if isinstance(entry, TaskStatus) else _of(entry)
        )
        public = self._speakers.get(origin)
        if signature is None or public is None:
            return False
        key = (topic, origin, inc, seq)
        data = signed_bytes(topic, origin, inc, seq, payload)
        if self._remembered.get(key) == (signature, data):
            return True  # heard before, the same payload with the same signature
        try:
            public.verify(signature, data, ec.ECDSA(hashes.SHA256()))
        except InvalidSignature:
            return False
        self._remember(key, signature, data)
        return True

    def remembered(self, topic: str, entry: AonEntry | TaskStatus) -> bytes | None:
        """The signature verified (or made) earlier for this message."""
        known = self._remembered.get((topic, entry.sender, entry.incarnation, entry.seq))
        return known[0] if known is not None else None

    # -- what a bus does with them --------------------------------------------------
    def checked(
        self, topic: str, message: Any, signatures: bytes, refuse: Callable[[str], None]
    ) -> Any:
        """A received message as far as its origins signed it: AON entries unsigned
        left out; a relayed copy whose status (or AON entries) its origin did not sign
        refused (None); a task status's signature remembered, for the copies relays
        make. ``refuse`` counts what is dropped (``unsigned_entry``)."""
        if topic in SIGNED_TOPICS:
            return self._signed_only(topic, message, signatures, refuse)
        if topic == TOPIC_TASK_STATUS:
            given = unpack_signatures(signatures)
            key = (message.sender, message.incarnation, message.seq)
            self.verify(topic, message, given.get(key))  # remembered when valid
            return message
        if topic != TOPIC_RELAYED:
            return message
        try:
            inner = decode(message.payload)
        except msgspec.DecodeError:
            return message  # the endpoint refuses it as a bad relay
        if isinstance(inner, TaskStatus):
            given = unpack_signatures(signatures)
            key = (inner.sender, inner.incarnation, inner.seq)
            if not self.verify(message.topic, inner, given.get(key)):
                refuse("unsigned_entry")
                return None
        elif isinstance(inner, AonMsg) and message.topic in SIGNED_TOPICS:
            kept = self._signed_only(message.topic, inner, signatures, refuse)
            if kept is not inner:
                return msgspec.structs.replace(message, payload=encode(kept))
        return message

    def signatures_for(self, topic: str, message: Message, own: Collection[str]) -> bytes:
        """The origin signatures that go with a message this process publishes: of
        the AON entries in it, of its own task statuses, and of what a relayed copy
        carries (``own``: the agents of this process)."""
        if isinstance(message, RelayedMsg):
            try:
                inner = decode(message.payload)
            except msgspec.DecodeError:
                return b""
            topic, message = message.topic, inner
        if isinstance(message, AonMsg) and topic in SIGNED_TOPICS:
            return self._sign_entries(topic, message, own)
        if isinstance(message, TaskStatus) and topic == TOPIC_TASK_STATUS:
            mine = message.sender in own
            signature = self.sign(topic, message) if mine else self.remembered(topic, message)
            if signature is not None:
                return pack_signatures(
                    [(message.sender, message.incarnation, message.seq, signature)]
                )
        return b""

    def _signed_only(
        self, topic: str, message: AonMsg, signatures: bytes, refuse: Callable[[str], None]
    ) -> AonMsg:
        """The AON message with the entries whose payload its origin did not sign left
        out (each counted: ``unsigned_entry``)."""
        given = unpack_signatures(signatures)
        kept = []
        for entry in message.entries:
            if entry.payload is not None:
                signature = given.get((entry.sender, entry.incarnation, entry.seq))
                if not self.verify(topic, entry, signature):
                    refuse("unsigned_entry")
                    continue
            kept.append(entry)
        if len(kept) == len(message.entries):
            return message
        return msgspec.structs.replace(message, entries=tuple(kept))

    def _sign_entries(self, topic: str, message: AonMsg, own: Collection[str]) -> bytes:
        """The origin signatures of an AON message's entries with a payload: this
        process's own made now, others' as verified when they arrived."""
        out = []
        for entry in message.entries:
            if entry.payload is None:
                continue
            mine = entry.sender in own
            signature = self.sign(topic, entry) if mine else self.remembered(topic, entry)
            if signature is not None:
                out.append((entry.sender, entry.incarnation, entry.seq, signature))
        return pack_signatures(out)

    def _remember(self, key: Key, signature: bytes, data: bytes) -> None:
        self._remembered[key] = (signature, data)
        self._remembered.move_to_end(key)
        while len(self._remembered) > MAX_REMEMBERED:
            self._remembered.popitem(last=False)


def _speakers(
    folder: Path, grants: tuple[tuple[str, tuple[str, ...]], ...]
) -> dict[str, ec.EllipticCurvePublicKey] | None:
    """Origin -> public key of the member certificate that may speak for it, from the
    members' certificates in ``folder`` (None when one is missing or not ECDSA)."""
    from cryptography import x509

    speakers: dict[str, ec.EllipticCurvePublicKey] = {}
    for member, chunks in grants:
        try:
            cert = x509.load_pem_x509_certificate((folder / f"{member}.pem").read_bytes())
        except (OSError, ValueError):
            return None
        public = cert.public_key()
        if not isinstance(public, ec.EllipticCurvePublicKey):
            return None
        speakers.update(dict.fromkeys(chunks, public))
    return speakers


def pack_signatures(signatures: list[tuple[str, int, int, bytes]]) -> bytes:
    """The attachment's tail: (origin, incarnation, seq, signature) of each entry."""
    return msgspec.msgpack.encode(signatures) if signatures else b""


def unpack_signatures(data: bytes) -> dict[tuple[str, int, int], bytes]:
    """What :func:`pack_signatures` packed (nothing for malformed bytes)."""
    if not data:
        return {}
    try:
        items: Any = msgspec.msgpack.decode(data, type=list[tuple[str, int, int, bytes]])
    except (msgspec.DecodeError, msgspec.ValidationError):
        return {}
    return {(origin, inc, seq): sig for origin, inc, seq, sig in items[:1024]}
