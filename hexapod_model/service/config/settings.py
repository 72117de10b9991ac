"""The service configuration ``fixture.toml``: bus, store, HTTP address and fixtures, validated.

Every field is checked when the file is read; an error names the file, the dotted field, the
value and what is expected (:class:`ConfigError`), and an unknown field is an error too (a
misspelt key is never silently ignored). Relative paths are relative to the file's folder.
The format, with every field and default: ``docs/service.md``; an example:
``docs/examples/fixture.toml``. Our defaults are ours, not an encoder maker's.
"""

from __future__ import annotations

import hashlib
import ipaddress
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import can

from ...description.presets import PRESETS
from ...exceptions import HexapodError
from ...kinematics.hexapod import Hexapod
from ...tracking.tracker import PREDICTORS
from ..errors import ConfigError
from .cell import Cell, cell_from_table
from .codec import FrameLayout, LegCodec
from .fieldbus import PROTOCOLS, CanopenEncoders, canopen_layout, dbc_layout
from .ros import RosConfig, ros_config
from .table import Table
from .tilt import TiltCodec, tilt_codec
from .token import read_token

INTERFACES = tuple(sorted(can.interfaces.VALID_INTERFACES))
NAME_PATTERN = re.compile(r"^[A-Za-z0-9_.-]+$")  # fixture names appear in URLs
MAX_LEGS = 12  # the six legs and up to six measuring legs
COUNTS = dict(enumerate("zero one two three four five six seven eight nine ten eleven twelve".split()))


@dataclass(frozen=True)
class BusConfig:
    """The CAN bus: a python-can ``interface`` and ``channel`` (``socketcan``/``can0`` on hardware)."""

    interface: str = "socketcan"
    channel: str = "can0"
    bitrate: int | None = None  # bit/s; only passed to python-can when given


@dataclass(frozen=True)
class StoreConfig:
    """The SQLite store: its file, the sample-log bound (rows) and the logging interval (s)."""

    path: Path
    samples: int = 100_000
    sample_interval: float = 0.0


@dataclass(frozen=True)
class HttpConfig:
    """The HTTP endpoint: address, access and limits.

    Attributes:
        host: address to bind (``127.0.0.1``: this machine only).
        port: port; 0 takes any free port (the service logs which).
        token_file: file holding the bearer token (mode 600), or None.
        token: the token read from ``token_file`` (never shown in a repr).
        allow_unauthenticated_reads: GET endpoints answer without the token (writes still need it).
        certfile: PEM certificate chain for HTTPS, with ``keyfile``; None: plain HTTP.
        keyfile: PEM private key of ``certfile``.
        max_connections: open connections served at once; more are answered ``503``.
        max_connections_per_address: connections of one client address beyond which its oldest
            one not in a request is closed for a new one.
        idle_timeout: s an idle connection (or one that sends no request) is kept open.
    """

    host: str = "127.0.0.1"
    port: int = 8765
    token_file: Path | None = None
    token: str | None = field(default=None, repr=False, compare=False)
    allow_unauthenticated_reads: bool = False
    certfile: Path | None = None
    keyfile: Path | None = None
    max_connections: int = 64
    max_connections_per_address: int = 32
    idle_timeout: float = 5.0

    @property
    def reads_need_token(self) -> bool:
        """GET endpoints need the token: one is configured and reads are not opened."""
        return self.token is not None and not self.allow_unauthenticated_reads


@dataclass(frozen=True)
class FixtureConfig:
    """One hexapod fixture and its encoders: the six legs', its measuring legs' and its inclinometer's.

    Attributes:
        name: URL-safe name (``/fixtures/NAME/pose``).
        hexapod: preset name or path of a URDF or geometry file.
        legs: one :class:`LegCodec` per leg, leg order (CAN id, layout, home count): the six
            legs, then the hexapod's measuring legs (``leg7``, ...), as many as it declares.
        noise: 1-sigma reading noise of an encoder (m): the source of the record's ``sigma``.
        staleness: a reading older than this (s) is not used; a leg silent longer is reported.
        lock_time: readings steady for this long (s) -> ``locked``.
        steady_band: readings within this band (m) count as steady (default 10 x noise).
        drift_limit: a locked fixture whose averaged readings move more (m) -> ``drift`` (default 3 x noise).
        unlock_samples: consecutive samples outside the band that unlock (one spike does not).
        stuck_sigmas: a leg whose count repeats exactly although its recent velocity predicts a
            change beyond this many ``noise`` is ``stuck`` (0: off).
        max_skew: largest spread (s) of the frame times of one reading set; 0 (default): 3/4 of
            the legs' measured frame period, for encoders sampled together (SYNC or polled) whose
            frames reach the bus in a burst shorter than that. A set completed by the next
            instant's first frame spans a period less one frame and is refused; when the burst
            fills more than half the period (1 kHz sets on a 1 Mbit/s bus) two frames lost in one
            set can go unseen: use a slower rate or fewer fixtures per bus.
        predictor: the tracker's predictor (``none``, ``eq22``, ``eq23``, ``eq24``).
        confirm_samples: consistent samples after a tracker jump before the branch is re-confirmed.
        process_wrench: force (N) and moment (N m) the process applies to the platform, platform frame,
            at ``wrench_point``; a locked fixture's records then carry the leg forces and the brakes' load
            margin at the lock pose (docs/statics.md). None: no ``load``.
        wrench_point: where the process force acts (m, platform frame).
        brake_capacity: axial force a brake holds (N); None: the geometry file's ``brake_capacity``.
        index: position in the file's ``[[fixtures]]`` list (for messages).
        cell: the base's placement in the robot cell and the coupling on the plate
            (``[fixtures.cell]``; ``None``: records carry no ``pose_in_robot``).
        protocol: the encoders' protocol, ``raw``, ``dbc`` or ``canopen``
            (:mod:`~hexapod_model.service.config.fieldbus`).
        canopen: the CANopen encoders' SYNC, EMCY and heartbeat (``protocol = "canopen"``), else None.
        inclinometer: the platform inclinometer's frame (``[fixtures.inclinometer]``), for a hexapod
            that declares one, else None.
    """

    name: str
    hexapod: str
    legs: tuple[LegCodec, ...]
    noise: float = 10e-6
    staleness: float = 0.05
    lock_time: float = 1.0
    steady_band: float = 100e-6
    drift_limit: float = 30e-6
    unlock_samples: int = 3
    stuck_sigmas: float = 8.0
    max_skew: float = 0.0
    predictor: str = "eq22"
    confirm_samples: int = 5
    process_wrench: tuple[float, ...] | None = None
    wrench_point: tuple[float, ...] = (0.0, 0.0, 0.0)
    brake_capacity: float | None = None
    index: int = 0
    source: str = field(default="<dict>", compare=False)
    cell: Cell | None = field(default=None, compare=False)
    protocol: str = "raw"
    canopen: CanopenEncoders | None = None
    inclinometer: TiltCodec | None = None

    def load_hexapod(self) -> Hexapod:
        """The fixture's :class:`Hexapod`; a file that cannot be read is a :class:`ConfigError`.

        Raises:
            ConfigError: the file cannot be read, or the configured encoders are not the
                hexapod's readings (:meth:`check_sensors`).
        """
        try:
            hexa = Hexapod.load(self.hexapod)
        except (HexapodError, OSError) as exc:
            reason = f"cannot load the hexapod: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"
            raise ConfigError(f"fixtures[{self.index}].hexapod", self.hexapod, reason, self.source) from None
        self.check_sensors(hexa)
        return hexa

    def check_sensors(self, hexa: Hexapod) -> None:
        """Refuse encoders that are not ``hexa``'s readings: one CAN id per leg, an inclinometer frame iff it has one.

        Raises:
            ConfigError: naming ``can_ids`` (legs) or ``inclinometer``, the hexapod's readings and the count found.
        """
        names = hexa.reading_names
        legs = [n for n in names if n.startswith("leg")]
        tilt = "tilt_x" in names
        where = f"fixtures[{self.index}]"
        if len(self.legs) != len(legs):
            reason = f"expected {len(legs)} CAN ids: the hexapod {self.hexapod} reads {', '.join(names)}"
            raise ConfigError(f"{where}.can_ids", [hex(leg.can_id) for leg in self.legs], reason, self.source)
        if tilt != (self.inclinometer is not None):
            reason = (
                f"the hexapod {self.hexapod} has an inclinometer (tilt_x, tilt_y): configure its frame"
                if tilt
                else f"the hexapod {self.hexapod} has no inclinometer"
            )
            value = None if self.inclinometer is None else hex(self.inclinometer.can_id)
            raise ConfigError(f"{where}.inclinometer", value, reason, self.source)

    @property
    def channels(self) -> int:
        """Encoder frames of one reading set: one per leg, one for the inclinometer."""
        return len(self.legs) + (self.inclinometer is not None)


@dataclass(frozen=True)
class ServiceConfig:
    """The whole ``fixture.toml``."""

    bus: BusConfig
    store: StoreConfig
    http: HttpConfig
    fixtures: tuple[FixtureConfig, ...]
    source: str = "<dict>"
    ros: RosConfig | None = None  # the optional [ros] table (hexapod_model.ros)

    def fixture(self, name: str) -> FixtureConfig:
        """The fixture called ``name`` (``KeyError`` when there is none)."""
        for f in self.fixtures:
            if f.name == name:
                return f
        raise KeyError(name)


def geometry_hash(hexa: Hexapod) -> str:
    """SHA-256 (hex) of the URDF (or MJCF) the hexapod was loaded from: stored with every lock pose."""
    clm = hexa.closed_loop
    text = clm.urdf_xml if clm.urdf_xml is not None else clm.mjcf_xml
    if text is None:
        raise ConfigError("hexapod", clm.source, "the model has no URDF or MJCF text to hash")
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def load_config(path: str | Path) -> ServiceConfig:
    """Read and validate ``fixture.toml``; :class:`ConfigError` names the first bad field."""
    path = Path(path)
    return config_from_dict(read_toml(path), str(path), path.parent)


def read_toml(path: Path) -> dict:
    """The TOML file ``path`` as a dict; :class:`ConfigError` when unreadable or not TOML."""
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError("<file>", str(path), f"cannot read: {exc.strerror or exc}", str(path)) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError("<file>", str(path), f"not valid TOML: {exc}", str(path)) from None


def config_from_dict(data: dict, source: str = "<dict>", folder: Path | None = None) -> ServiceConfig:
    """Validate a parsed configuration; relative paths are taken relative to ``folder``."""
    folder = folder or Path(".")
    top = Table(data, "", source)
    b = top.table("bus", {})
    bus = BusConfig(
        interface=b.text("interface", "socketcan", INTERFACES),
        channel=b.text("channel", "can0"),
        bitrate=b.integer("bitrate", 0, 0, 10_000_000) or None,
    )
    b.finish()
    s = top.table("store", {})
    stem = Path(source).stem if source != "<dict>" else "fixture"
    store = StoreConfig(
        path=folder / s.text("path", f"{stem}.sqlite"),
        samples=s.integer("samples", 100_000, 0, 10**9),
        sample_interval=s.number("sample_interval", 0.0, 0.0, 3600.0),
    )
    s.finish()
    http = _http(top.table("http", {}), folder)
    items = top.take("fixtures")
    if not isinstance(items, list) or not items:
        raise top.error("fixtures", items, "expected one or more [[fixtures]] tables")
    fixtures = tuple(_fixture(Table(f, f"fixtures[{i}]", source), i, folder) for i, f in enumerate(items))
    ros = None if "ros" not in data else ros_config(top.table("ros"))
    top.finish()
    _check_unique(fixtures, source)
    return ServiceConfig(bus, store, http, fixtures, source, ros=ros)


def _http(h: Table, folder: Path) -> HttpConfig:
    host = h.text("host", "127.0.0.1")
    token_file = _path(h, "token_file", folder)
    token = None if token_file is None else read_token(token_file, h.name("token_file"), h.source)
    certfile, keyfile = _path(h, "certfile", folder), _path(h, "keyfile", folder)
    if (certfile is None) != (keyfile is None):
        key = "keyfile" if keyfile is None else "certfile"
        raise h.error(key, None, "HTTPS needs both certfile and keyfile")
    for key, p in (("certfile", certfile), ("keyfile", keyfile)):
        if p is not None and not p.is_file():
            raise h.error(key, str(p), "not a readable file")
    http = HttpConfig(
        host=host,
        port=h.integer("port", 8765, 0, 65535),
        token_file=token_file,
        token=token,
        allow_unauthenticated_reads=h.boolean("allow_unauthenticated_reads", False),
        certfile=certfile,
        keyfile=keyfile,
        max_connections=h.integer("max_connections", 64, 1, 10_000),
        max_connections_per_address=h.integer("max_connections_per_address", 32, 1, 10_000),
        idle_timeout=h.number("idle_timeout", 5.0, 0.1, 3600.0),
    )
    if token is None and not http.allow_unauthenticated_reads and not is_loopback(host):
        raise h.error(
            "host",
            host,
            "serving beyond this machine needs [http] token_file (or allow_unauthenticated_reads = true)",
        )
    h.finish()
    return http


def is_loopback(host: str) -> bool:
    """Whether ``host`` names this machine only (``localhost`` or a loopback address)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _path(t: Table, key: str, folder: Path) -> Path | None:
    value = t.take(key, None)
    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise t.error(key, value, "expected a file path")
    p = Path(value)
    return p if p.is_absolute() else folder / p


def _hexapod_spec(t: Table, folder: Path) -> str:
    spec = t.text("hexapod")
    if spec in PRESETS:
        return spec
    p = Path(spec) if Path(spec).is_absolute() else folder / spec
    if p.is_dir():
        raise t.error("hexapod", spec, f"{p} is a folder: give a URDF or geometry file in it, or a preset")
    if not p.is_file():
        raise t.error("hexapod", spec, f"neither a preset ({', '.join(PRESETS)}) nor a file ({p} does not exist)")
    try:
        with p.open("rb"):
            pass
    except OSError as exc:
        raise t.error("hexapod", spec, f"cannot read {p}: {exc.strerror or exc}") from None
    return str(p)


def _numbers(t: Table, key: str, n: int, default: tuple[float, ...] | None) -> tuple[float, ...] | None:
    """``n`` finite numbers under ``key`` (a TOML array), or ``default`` when absent."""
    raw = t.take(key, None)
    if raw is None:
        return default
    if not isinstance(raw, list) or len(raw) != n:
        raise t.error(key, raw, f"expected {n} numbers")
    sub = Table({f"{key}[{k}]": v for k, v in enumerate(raw)}, t.where, t.source)
    return tuple(sub.number(f"{key}[{k}]") for k in range(n))


def _fixture(t: Table, index: int, folder: Path) -> FixtureConfig:
    name = t.text("name")
    if not NAME_PATTERN.match(name) or set(name) == {"."}:
        raise t.error("name", name, "use letters, digits, '_', '-' and '.' only, not dots alone (it appears in URLs)")
    spec = _hexapod_spec(t, folder)
    extended = t.boolean("extended_id", False)
    id_max = 0x1FFFFFFF if extended else 0x7FF
    ids = t.take("can_ids")
    if not isinstance(ids, list) or not 6 <= len(ids) <= MAX_LEGS:
        raise t.error("can_ids", ids, f"expected 6 to {MAX_LEGS} CAN ids, leg order (the six legs, then leg7, ...)")
    n = len(ids)
    sub = Table({f"can_ids[{k}]": v for k, v in enumerate(ids)}, t.where, t.source)
    can_ids = [sub.integer(f"can_ids[{k}]", lo=0, hi=id_max) for k in range(n)]
    homes = t.take("home_counts", 0)
    if isinstance(homes, int) and not isinstance(homes, bool):
        homes = [homes] * n
    if not isinstance(homes, list) or len(homes) != n:
        raise t.error("home_counts", homes, f"expected one integer or {COUNTS[n]}, one per CAN id (leg order)")
    sub = Table({f"home_counts[{k}]": v for k, v in enumerate(homes)}, t.where, t.source)
    home_counts = [sub.integer(f"home_counts[{k}]", lo=-(2**63), hi=2**64) for k in range(n)]
    encoder = t.table("encoder", {})
    protocol = encoder.text("protocol", "raw", PROTOCOLS)
    canopen = None
    if protocol == "dbc":
        layout = dbc_layout(encoder, folder)
    elif protocol == "canopen":
        if extended:
            raise t.error("extended_id", True, "CANopen COB-IDs are 11-bit")
        layout, canopen = canopen_layout(encoder, folder, can_ids)
    else:
        layout = FrameLayout.from_table(encoder)
    inclinometer = None
    if "inclinometer" in t.data:
        if protocol == "canopen":
            raise t.error("inclinometer", t.data["inclinometer"], "not read with protocol = 'canopen' (raw or dbc)")
        inclinometer = tilt_codec(t.table("inclinometer"), id_max, extended)
    lo, hi = layout.count_range
    for k, c in enumerate(home_counts):
        if not lo <= c <= hi:
            raise t.error(f"home_counts[{k}]", c, f"outside the count field [{lo}, {hi}] of the encoder layout")
    noise = t.number("noise", 10e-6, 0.0, 0.01)
    staleness = t.number("staleness", 0.05, 1e-4, 60.0)
    cfg = FixtureConfig(
        name=name,
        hexapod=spec,
        legs=tuple(LegCodec(i, layout, h, extended) for i, h in zip(can_ids, home_counts)),
        noise=noise,
        staleness=staleness,
        lock_time=t.number("lock_time", 1.0, 0.0, 3600.0),
        steady_band=t.number("steady_band", 10 * noise, 1e-9, 0.1),
        drift_limit=t.number("drift_limit", 3 * noise, 1e-9, 0.1),
        unlock_samples=t.integer("unlock_samples", 3, 1, 1000),
        stuck_sigmas=t.number("stuck_sigmas", 8.0, 0.0, 1e6),
        max_skew=t.number("max_skew", 0.0, 0.0, 60.0),
        predictor=t.text("predictor", "eq22", PREDICTORS),
        confirm_samples=t.integer("confirm_samples", 5, 1, 10_000),
        process_wrench=_numbers(t, "process_wrench", 6, None),
        wrench_point=_numbers(t, "wrench_point", 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
        brake_capacity=t.number("brake_capacity", None, 1e-9, 1e9) if "brake_capacity" in t.data else None,
        index=index,
        source=t.source,
        cell=cell_from_table(t.table("cell")) if "cell" in t.data else None,
        protocol=protocol,
        canopen=canopen,
        inclinometer=inclinometer,
    )
    if cfg.drift_limit >= cfg.steady_band:
        raise t.error("drift_limit", cfg.drift_limit, f"must be below steady_band = {cfg.steady_band:g} m")
    t.finish()
    return cfg


def _check_unique(fixtures: tuple[FixtureConfig, ...], source: str) -> None:
    names: dict[str, int] = {}
    ids: dict[tuple[int, bool], str] = {}
    for f in fixtures:
        if f.name in names:
            raise ConfigError(
                f"fixtures[{f.index}].name", f.name, f"also the name of fixtures[{names[f.name]}]", source
            )
        names[f.name] = f.index
        for k, leg in enumerate(f.legs):
            here = f"fixtures[{f.index}].can_ids[{k}]"
            key = (leg.can_id, leg.extended_id)
            if key in ids:
                raise ConfigError(here, hex(leg.can_id), f"duplicate CAN id: also {ids[key]} (one bus)", source)
            ids[key] = here
        if f.inclinometer is not None:
            here = f"fixtures[{f.index}].inclinometer.can_id"
            key = (f.inclinometer.can_id, f.inclinometer.extended_id)
            if key in ids:
                raise ConfigError(here, hex(key[0]), f"duplicate CAN id: also {ids[key]} (one bus)", source)
            ids[key] = here
        if f.canopen is not None:  # EMCY and heartbeat ids: the SYNC is shared by every CANopen fixture
            for can_id in f.canopen.ids()[1:]:
                here = f"fixtures[{f.index}].encoder (EMCY/heartbeat of node {can_id & 0x7F})"
                if (can_id, False) in ids:
                    why = f"duplicate CAN id: also {ids[(can_id, False)]} (one bus)"
                    raise ConfigError(here, hex(can_id), why, source)
                ids[(can_id, False)] = here
