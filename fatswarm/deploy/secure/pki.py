"""`fatswarm secure`: a certificate authority, one certificate per part, and each part's Zenoh
configuration (mutual TLS, access control with default deny), written to one folder.

The plan (identities, ACL, configurations) is `deploy/secure/plan.py`; this module issues the
certificates with the `cryptography` package (`pip install "fatswarm[secure]"`) and writes files.
The authority's private key is never written: nobody can mint a new identity for the swarm later
(to add a part, generate the swarm's folder anew and deploy it everywhere).
"""

from __future__ import annotations

import argparse
import datetime
import ipaddress
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fatswarm.deploy.secure.plan import (
    CA_FILE,
    DEFAULT_PORT,
    LOOPBACK,
    Identity,
    Plan,
    config_name,
    config_text,
    files_of,
    is_ip,
)
from fatswarm.domain.outcome import ExitCode

if TYPE_CHECKING:
    from cryptography import x509
    from cryptography.hazmat.primitives.asymmetric import ec

DEFAULT_DAYS = 365
EXTRA = 'pip install "fatswarm[secure]"'
README = "README.txt"


class MissingCryptography(RuntimeError):
    """The optional `cryptography` package is not installed."""


@dataclass(frozen=True, slots=True)
class Issued:
    """A private key and its certificate, as PEM bytes."""

    key_pem: bytes
    cert_pem: bytes


def _require_cryptography() -> None:
    try:  # cryptography is an optional extra (fatswarm[secure]): without it, say how to get it
        import cryptography  # noqa: F401
    except ImportError:
        raise MissingCryptography(f"certificates need the cryptography package: {EXTRA}") from None


def issue_all(plan: Plan, days: int = DEFAULT_DAYS) -> tuple[bytes, dict[str, Issued]]:
    """The authority's certificate and every identity's key and certificate (EC P-256), by name.

    Routers' certificates name their host (IP or DNS) and loopback (127.0.0.1, localhost) as
    subject alternative names, which clients and other routers check on connecting; every
    certificate's common name is its identity.
    """
    _require_cryptography()
    # cryptography is an optional extra (fatswarm[secure]), checked just above
    from cryptography import x509
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    if days < 1:
        raise ValueError(f"--days must be at least 1, got {days}")
    start = datetime.datetime.now(datetime.UTC) - datetime.timedelta(minutes=5)  # clock skew
    end = start + datetime.timedelta(days=days)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, f"fatswarm {plan.swarm} CA")])
    ca_cert = _ca_certificate(ca_key, ca_name, start, end)
    issued: dict[str, Issued] = {}
    for who in plan.identities:
        issued[who.name] = _issue(who, ca_key, ca_name, start, end)
    return ca_cert.public_bytes(serialization.Encoding.PEM), issued


def _ca_certificate(
    ca_key: ec.EllipticCurvePrivateKey,
    ca_name: x509.Name,
    start: datetime.datetime,
    end: datetime.datetime,
) -> x509.Certificate:
    """The authority's self-signed certificate: it signs certificates, nothing else."""
    # the optional cryptography package (issue_all checked it)
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes

    return (
        x509.CertificateBuilder()
        .subject_name(ca_name)
        .issuer_name(ca_name)
        .public_key(ca_key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(_key_usage(signs_certificates=True), critical=True)
        .add_extension(
            x509.SubjectKeyIdentifier.from_public_key(ca_key.public_key()), critical=False
        )
        .sign(ca_key, hashes.SHA256())
    )


def _issue(
    who: Identity,
    ca_key: ec.EllipticCurvePrivateKey,
    ca_name: x509.Name,
    start: datetime.datetime,
    end: datetime.datetime,
) -> Issued:
    """A new key for `who` and its certificate, signed by the authority."""
    # the optional cryptography package (issue_all checked it)
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    usages = [ExtendedKeyUsageOID.CLIENT_AUTH]
    if who.role == "router":  # it also accepts links, and links to the other routers
        usages.append(ExtendedKeyUsageOID.SERVER_AUTH)
    builder = (
        x509.CertificateBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, who.name)]))
        .issuer_name(ca_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(_key_usage(signs_certificates=False), critical=True)
        .add_extension(x509.ExtendedKeyUsage(usages), critical=False)
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()),
            critical=False,
        )
        .add_extension(x509.SubjectAlternativeName(_alt_names(who)), critical=False)
    )
    cert = builder.sign(ca_key, hashes.SHA256())
    return Issued(
        key.private_bytes(
            serialization.Encoding.PEM,
            serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption(),
        ),
        cert.public_bytes(serialization.Encoding.PEM),
    )


def _key_usage(*, signs_certificates: bool) -> x509.KeyUsage:
    """The authority's key usage (signs certificates and revocation lists) or an identity's
    (digital signatures only)."""
    from cryptography import x509  # the optional cryptography package (issue_all checked it)

    return x509.KeyUsage(
        digital_signature=not signs_certificates,
        content_commitment=False,
        key_encipherment=False,
        data_encipherment=False,
        key_agreement=False,
        key_cert_sign=signs_certificates,
        crl_sign=signs_certificates,
        encipher_only=False,
        decipher_only=False,
    )


def _alt_names(who: Identity) -> list[Any]:
    from cryptography import x509  # the optional cryptography package (issue_all checked it)

    if who.host is None:  # a client: its name, never checked (the routers match the CN)
        return [x509.DNSName(who.name)]
    names: list[Any] = [x509.IPAddress(ipaddress.ip_address(LOOPBACK)), x509.DNSName("localhost")]
    if who.host == LOOPBACK:
        return names
    if is_ip(who.host):
        return [x509.IPAddress(ipaddress.ip_address(who.host)), *names]
    return [x509.DNSName(who.host), *names]


# --- the folder --------------------------------------------------------------------------------


def write_bundle(
    plan: Plan, out: Path, force: bool = False, days: int = DEFAULT_DAYS
) -> list[Path]:
    """Write the swarm's folder `out`: ca.pem, and per identity NAME.key (mode 0600), NAME.pem and
    NAME.json5; returns the paths written. The folder is made whole in a temporary sibling and
    then renamed, so a failure leaves no half folder.

    Raises FileExistsError if `out` exists (unless `force`: then it is replaced whole).
    """
    out = Path(out)
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists: pick another --out, or --force to replace it")
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"{out} exists and is not a folder: --force replaces only a folder")
    parent = out.resolve().parent
    if not parent.is_dir():
        raise FileNotFoundError(f"the folder {parent} of --out does not exist")
    ca_pem, issued = issue_all(plan, days)
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=parent))
    try:
        written = [_write(work / CA_FILE, ca_pem, 0o644)]
        for who in plan.identities:
            key_file, cert_file = files_of(who)
            written.append(_write(work / key_file, issued[who.name].key_pem, 0o600))
            written.append(_write(work / cert_file, issued[who.name].cert_pem, 0o644))
            written.append(_write(work / config_name(who), config_text(plan, who).encode(), 0o644))
        written.append(_write(work / README, readme_text(plan).encode(), 0o644))
        os.chmod(work, 0o700)  # it holds every private key: copy each host only its own
        if out.exists():
            shutil.rmtree(out)
        os.replace(work, out)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    return [out / p.name for p in written]


def _write(path: Path, data: bytes, mode: int) -> Path:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.chmod(path, mode)
    return path


def readme_text(plan: Plan) -> str:
    """What the folder holds, which files each host needs, and the commands, run in the folder."""
    local, swarm = plan.local_endpoint, plan.swarm
    lines = [
        f"fatswarm secure: swarm {swarm!r}, {plan.n} robots, routers on "
        f"{', '.join(plan.hosts)} (TLS port {plan.port}).",
        "",
        "Each part needs ca.pem and its own NAME.key, NAME.pem and NAME.json5: copy each host",
        "only the files of the parts it runs (a .key file is that part's identity). Each router",
        f"listens on its host's address and on {local}, where the parts on its host connect.",
        "S is the run's seed: the same for the world and the coordinator.",
        "",
        "# on each host, its router:",
        *(f"fatswarm router --config router-{host}.json5" for host in plan.hosts),
        "# the world and the coordinator, on one host:",
        f"fatswarm world --config world.json5 --connect {local} --swarm {swarm} -n {plan.n} "
        f"--seed S --state {swarm}.jsonl",
        f"fatswarm coordinator --config coordinator.json5 --connect {local} --swarm {swarm} "
        "--seed S",
        "# agents, on any hosts, each with its own identity ({robot} becomes its id):",
        f"fatswarm agents --config 'agent-{{robot}}.json5' --connect {local} --swarm {swarm} "
        f"-n {plan.n} --first 0",
    ]
    if plan.dashboards:
        lines += [
            "# a read-only dashboard, on any host:",
            f"fatswarm dashboard --config dashboard-0.json5 --connect {local} --swarm {swarm}",
        ]
    lines += ["", "Who may do what, and why: docs/security.md of fatswarm."]
    return "\n".join(lines) + "\n"


# --- the command -------------------------------------------------------------------------------


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm secure`."""
    p.description = (
        "Make a folder with everything a swarm needs to run on several hosts secured: a "
        "certificate authority (ca.pem; its private key is not kept), one private key and "
        "certificate per part (each router, the world, the coordinator, every robot's agent, "
        "the dashboards), and each part's Zenoh configuration (NAME.json5) for --config: mutual "
        "TLS only, and, on the routers, access control with default deny, so that robot i may "
        "only publish its own moves and ask its own snapshot, only the coordinator may open and "
        "commit rounds, only the world may answer snapshots and control, and dashboards may "
        "only read the state. Needs the cryptography package (" + EXTRA + ")."
    )
    p.add_argument("--swarm", required=True, help="the swarm's name (its keys: fatswarm/<swarm>/)")
    p.add_argument("-n", type=int, required=True, metavar="N", help="number of robots")
    p.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="the folder to create (refused if it exists, unless --force)",
    )
    p.add_argument(
        "--hosts",
        action="append",
        default=[],
        metavar="ADDRESS[,ADDRESS...]",
        help="the routers' hosts, one router each, by the IP address or DNS name the "
        "others reach it at (repeatable or comma-separated; default 127.0.0.1); each "
        "router links to the ones listed before it",
    )
    p.add_argument(
        "--port",
        type=int,
        default=DEFAULT_PORT,
        help=f"the routers' TLS port (default {DEFAULT_PORT})",
    )
    p.add_argument(
        "--dashboards",
        type=int,
        default=1,
        metavar="K",
        help="dashboard identities to make (default 1)",
    )
    p.add_argument(
        "--days",
        type=int,
        default=DEFAULT_DAYS,
        help=f"how long the certificates are valid (default {DEFAULT_DAYS})",
    )
    p.add_argument("--force", action="store_true", help="replace an existing --out folder")


def main(args: argparse.Namespace) -> int:
    """`fatswarm secure`: write the folder; one line on stderr and exit 2 for bad input."""
    hosts = [h.strip() for entry in args.hosts for h in entry.split(",")] or ["127.0.0.1"]
    try:
        if any(not h for h in hosts):
            raise ValueError("--hosts has an empty entry")
        plan = Plan(args.swarm, args.n, tuple(hosts), args.port, args.dashboards)
        written = write_bundle(plan, Path(args.out), args.force, args.days)
    except (ValueError, OSError, MissingCryptography) as exc:
        print(f"fatswarm secure: {_said(exc)}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    print(
        f"fatswarm secure: wrote {len(written)} files to {args.out} for swarm {plan.swarm!r} "
        f"({len(plan.identities)} identities); see {Path(args.out) / README}",
        file=sys.stderr,
    )
    return 0


def _said(exc: BaseException) -> str:
    if isinstance(exc, OSError) and not isinstance(exc, (FileExistsError, FileNotFoundError)):
        where = f" ({exc.filename})" if exc.filename else ""
        return f"cannot write the folder: {(exc.strerror or str(exc)).lower()}{where}"
    if isinstance(exc, (FileExistsError, FileNotFoundError)) and exc.args and not exc.filename:
        return str(exc.args[0])
    return str(exc)
