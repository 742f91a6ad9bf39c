"""`fatswarm secure` and `--config`, without a network: the access control names exactly each
part's own keys, the files are written (and refused when they would overwrite), bad input is one
line, and a --config file is read as documented."""

from __future__ import annotations

import datetime
import json
import os
import re
import stat
from pathlib import Path

import pytest
import zenoh

from fatswarm.deploy import cli
from fatswarm.deploy.net.part_common import config_for
from fatswarm.deploy.net.zconf import (
    ZenohSetupError,
    connect_endpoints,
    listen_endpoints,
    load_config_file,
    make_config,
    unreachable_message,
)
from fatswarm.deploy.secure import pki
from fatswarm.deploy.secure.plan import (
    MESSAGES,
    Grant,
    Identity,
    Plan,
    access_control,
    config_name,
    config_text,
    files_of,
    grants,
    matrix,
    part_config,
)
from fatswarm.domain.outcome import ExitCode

SWARM = "lab"
P = f"fatswarm/{SWARM}"
N = 4
PLAN = Plan(SWARM, N, ("10.0.0.1", "10.0.0.2", "host-c.example"), 7447, 2)


def _chunk_includes(rule: str, key: str) -> bool:
    return rule == key or (rule == "*" and key != "**")


def includes(rule: str, key: str) -> bool:
    """Whether key expression `rule` includes every key of `key` (enough of Zenoh's semantics for
    the chunks used here: literals, `*`, and a trailing `**`)."""
    r, k = rule.split("/"), key.split("/")
    if r[-1] == "**":
        r = r[:-1]
        return len(k) >= len(r) and all(map(_chunk_includes, r, k[: len(r)]))
    return len(r) == len(k) and all(map(_chunk_includes, r, k))


def may(who: str, flow: str, message: str, key: str, plan: Plan = PLAN) -> bool:
    """What the ACL lets `who` do, read back from the access_control block as Zenoh reads it:
    allowed if a rule of its policy, for this flow and message, includes the key; else denied."""
    acl = access_control(plan)
    assert acl["default_permission"] == "deny"
    subjects = {s["id"] for s in acl["subjects"] if who in s["cert_common_names"]}
    rule_ids = {r for p in acl["policies"] if set(p["subjects"]) & subjects for r in p["rules"]}
    return any(
        includes(k, key)
        for rule in acl["rules"]
        if rule["id"] in rule_ids
        and rule["permission"] == "allow"
        and flow in rule["flows"]
        and message in rule["messages"]
        for k in rule["key_exprs"]
    )


# --- who may do what -------------------------------------------------------------------------


def test_an_agent_sends_only_its_own_look_which_carries_its_move_and_its_token() -> None:
    sent = {
        (g.message, g.key)
        for g in grants(SWARM, Identity("agent-2", "agent", robot=2))
        if g.flow == "ingress"
    }
    assert sent == {
        ("query", f"{P}/robot/2/snapshot"),
        ("liveliness_token", f"{P}/alive/agent/2"),
        ("declare_liveliness_subscriber", f"{P}/alive/world"),
    }


def test_an_agent_receives_only_its_own_snapshot_and_that_the_world_listens() -> None:
    got = {
        (g.message, g.key)
        for g in grants(SWARM, Identity("agent-2", "agent", robot=2))
        if g.flow == "egress"
    }
    assert got == {
        ("reply", f"{P}/robot/2/snapshot"),
        ("declare_queryable", f"{P}/robot/*/snapshot"),
        ("liveliness_token", f"{P}/alive/world"),
    }  # it asks again when a world is up


@pytest.mark.parametrize(
    ("who", "message", "key"),
    [
        ("agent-1", "put", f"{P}/robot/2/move"),  # a move for another robot
        ("agent-1", "put", f"{P}/robot/1/move"),  # its own: moves travel in its Look only
        ("agent-1", "query", f"{P}/robot/2/snapshot"),  # another robot's snapshot
        ("agent-1", "query", f"{P}/world/control"),  # Begin/Commit as the coordinator
        ("agent-1", "liveliness_token", f"{P}/alive/agent/2"),  # a fake agent
        ("agent-1", "liveliness_token", f"{P}/alive/agent/9"),
        ("agent-1", "declare_queryable", f"{P}/robot/*/snapshot"),  # a fake world
        ("agent-1", "declare_queryable", f"{P}/robot/1/snapshot"),
        ("agent-1", "reply", f"{P}/robot/2/snapshot"),
        ("agent-1", "put", f"{P}/world/moves"),  # fake moves-held notices
        ("agent-1", "declare_queryable", f"{P}/world/control"),  # a fake ControlReply
        ("agent-1", "reply", f"{P}/world/control"),
        ("agent-1", "declare_subscriber", f"{P}/world/state"),  # agents do not read the state
        ("agent-1", "declare_subscriber", f"{P}/robot/*/move"),
        ("dashboard-0", "put", f"{P}/world/state"),
        ("dashboard-0", "put", f"{P}/robot/0/move"),
        ("dashboard-0", "query", f"{P}/world/control"),
        ("dashboard-0", "query", f"{P}/robot/0/snapshot"),
        ("dashboard-0", "declare_subscriber", f"{P}/robot/*/move"),
        ("dashboard-0", "declare_subscriber", f"{P}/**"),
        ("dashboard-0", "liveliness_token", f"{P}/alive/agent/0"),
        ("dashboard-0", "liveliness_token", f"{P}/alive/world"),
        ("coordinator", "put", f"{P}/robot/0/move"),
        ("coordinator", "declare_queryable", f"{P}/world/control"),
        ("coordinator", "reply", f"{P}/world/control"),
        ("coordinator", "put", f"{P}/world/moves"),
        ("coordinator", "liveliness_token", f"{P}/alive/world"),
        ("world", "query", f"{P}/world/control"),
        ("world", "put", f"{P}/robot/0/move"),
        ("world", "liveliness_token", f"{P}/alive/coordinator"),
        ("world", "liveliness_token", f"{P}/alive/agent/0"),
        ("stranger", "put", f"{P}/robot/0/move"),  # a certificate name the ACL does not know
        ("router-10.0.0.1", "put", "fatswarm/other/robot/0/move"),  # another swarm
        ("agent-1", "put", f"{P}/coordinator/round"),  # the old round announcement key: nobody
        ("coordinator", "put", f"{P}/coordinator/round"),
    ],
)
def test_every_rogue_try_is_denied(who: str, message: str, key: str) -> None:
    assert not may(who, "ingress", message, key)


@pytest.mark.parametrize(
    ("who", "message", "key"),
    [
        ("agent-3", "query", f"{P}/robot/3/snapshot"),
        ("agent-3", "liveliness_token", f"{P}/alive/agent/3"),
        ("coordinator", "query", f"{P}/world/control"),
        ("coordinator", "declare_subscriber", f"{P}/world/moves"),
        ("coordinator", "declare_liveliness_subscriber", f"{P}/alive/agent/*"),
        ("coordinator", "declare_liveliness_subscriber", f"{P}/alive/world"),
        ("coordinator", "liveliness_query", f"{P}/alive/coordinator"),
        ("coordinator", "liveliness_token", f"{P}/alive/coordinator"),
        ("world", "declare_queryable", f"{P}/robot/*/snapshot"),
        ("world", "reply", f"{P}/robot/3/snapshot"),
        ("world", "declare_queryable", f"{P}/world/control"),
        ("world", "reply", f"{P}/world/control"),
        ("world", "put", f"{P}/world/state"),
        ("world", "put", f"{P}/world/moves"),
        ("world", "liveliness_token", f"{P}/alive/world"),
        ("world", "liveliness_query", f"{P}/alive/world"),
        ("world", "declare_liveliness_subscriber", f"{P}/alive/agent/*"),
        ("dashboard-1", "declare_subscriber", f"{P}/world/state"),
        ("dashboard-1", "declare_liveliness_subscriber", f"{P}/alive/agent/*"),
        ("router-host-c.example", "put", f"{P}/robot/3/move"),
        ("router-10.0.0.2", "reply", f"{P}/world/control"),
    ],
)
def test_each_part_may_do_its_own_job(who: str, message: str, key: str) -> None:
    assert may(who, "ingress", message, key)


def test_only_the_world_answers_and_only_the_coordinator_asks_control() -> None:
    parts = [w for w in PLAN.identities if w.role != "router"]
    for message, key, only in [
        ("reply", f"{P}/robot/0/snapshot", {"world"}),
        ("declare_queryable", f"{P}/robot/*/snapshot", {"world"}),
        ("reply", f"{P}/world/control", {"world"}),
        ("put", f"{P}/world/state", {"world"}),
        ("put", f"{P}/world/moves", {"world"}),
        ("query", f"{P}/world/control", {"coordinator"}),
        ("put", f"{P}/robot/0/move", set()),
        ("query", f"{P}/robot/0/snapshot", {"agent-0"}),
        ("liveliness_token", f"{P}/alive/agent/0", {"agent-0"}),
        ("liveliness_token", f"{P}/alive/coordinator", {"coordinator"}),
    ]:
        assert {w.name for w in parts if may(w.name, "ingress", message, key)} == only, key


def test_no_grant_uses_a_delete_or_leaves_the_swarm() -> None:
    for who in PLAN.identities:
        for g in grants(SWARM, who):
            assert g.key.startswith(f"{P}/"), g
            assert g.message in MESSAGES and g.flow in ("ingress", "egress"), g
            assert "coordinator/round" not in g.key, g
            if who.role != "router":
                assert g.message != "delete", g


def test_the_acl_block_is_one_subject_and_policy_per_identity_and_zenoh_reads_it() -> None:
    acl = access_control(PLAN)
    names = [w.name for w in PLAN.identities]
    assert [s["id"] for s in acl["subjects"]] == names
    assert [s["cert_common_names"] for s in acl["subjects"]] == [[n] for n in names]
    rule_ids = [r["id"] for r in acl["rules"]]
    assert len(set(rule_ids)) == len(rule_ids)
    for policy in acl["policies"]:
        assert set(policy["rules"]) <= set(rule_ids)
    assert (acl["enabled"], acl["default_permission"]) == (True, "deny")
    zenoh.Config.from_json5(json.dumps({"access_control": acl}))  # message names Zenoh knows


def test_the_documented_matrix_is_the_one_built() -> None:
    doc = (Path(__file__).parents[2] / "docs" / "security.md").read_text()
    table = doc.split("<!-- matrix: generated by deploy.secure.matrix() -->")[1]
    table = table.split("<!-- end of matrix -->")[0]
    rows = [
        tuple(c.strip().strip("`") for c in line.strip().strip("|").split("|"))
        for line in table.strip().splitlines()[2:]
    ]
    assert rows == [r for r in matrix() if not r[0].startswith("router")]
    assert {r[2:] for r in matrix() if r[0].startswith("router")} == {(m, "**") for m in MESSAGES}


def test_no_message_on_the_wire_carries_a_seed_or_a_frame() -> None:
    """Seeds and private flips are never published: a robot's frame follows from the run's seed,
    which the agents get on their command line only."""
    import dataclasses

    from fatswarm.world import observers
    from fatswarm.world import protocol as world_wire

    messages = [
        c
        for m in (world_wire, observers)
        for c in vars(m).values()
        if isinstance(c, type) and dataclasses.is_dataclass(c) and c.__module__ == m.__name__
    ]
    assert {c.__name__ for c in messages} >= {"WorldState", "Snapshot", "MoveSubmitted"}
    for message in messages:
        for f in dataclasses.fields(message):
            assert "seed" not in f.name and "flip" not in f.name, (message.__name__, f.name)


def test_grants_follow_the_protocol_functions(monkeypatch: pytest.MonkeyPatch) -> None:
    from fatswarm.world import protocol as world_wire

    monkeypatch.setattr(world_wire, "snapshot_key", lambda swarm, robot: f"x/{swarm}/s/{robot}")
    assert Grant("ingress", "query", "x/lab/s/1") in grants(
        SWARM, Identity("agent-1", "agent", robot=1)
    )


# --- the plan and the configurations ---------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        ({"swarm": "a b"}, "swarm name must be"),
        ({"n": 0}, "-n must be in 1..4096"),
        ({"hosts": ()}, "at least one router host"),
        ({"hosts": ("0.0.0.0",)}, "a wildcard address"),
        ({"hosts": ("1.2.3",)}, "not an IPv4 address"),
        ({"hosts": ("bad_name!",)}, "neither an IP address nor a host name"),
        ({"hosts": ("10.0.0.1", "10.0.0.1")}, "names a host twice"),
        ({"port": 0}, "--port must be"),
        ({"dashboards": -1}, "--dashboards must be"),
    ],
)
def test_a_bad_plan_says_what_to_fix(kwargs: dict[str, object], said: str) -> None:
    base: dict[str, object] = {"swarm": SWARM, "n": 2, "hosts": ("127.0.0.1",)}
    with pytest.raises(ValueError, match=re.escape(said)):
        Plan(**{**base, **kwargs})  # type: ignore[arg-type]


def test_the_identities_are_routers_world_coordinator_agents_dashboards() -> None:
    assert [w.name for w in PLAN.identities] == [
        "router-10.0.0.1",
        "router-10.0.0.2",
        "router-host-c.example",
        "world",
        "coordinator",
        "agent-0",
        "agent-1",
        "agent-2",
        "agent-3",
        "dashboard-0",
        "dashboard-1",
    ]


def test_routers_listen_on_tls_link_each_pair_once_and_hold_the_acl() -> None:
    a, b, c = PLAN.routers
    confs = [part_config(PLAN, r) for r in (a, b, c)]
    local = "tls/127.0.0.1:7447"  # the parts on a router's own host
    assert [x["listen"]["endpoints"] for x in confs] == [
        ["tls/10.0.0.1:7447", local],
        ["tls/10.0.0.2:7447", local],
        ["tls/host-c.example:7447", local],
    ]
    assert [x["connect"]["endpoints"] for x in confs] == [
        [],
        ["tls/10.0.0.1:7447"],
        ["tls/10.0.0.1:7447", "tls/10.0.0.2:7447"],
    ]
    for x, r in zip(confs, (a, b, c), strict=True):
        assert x["mode"] == "router" and x["access_control"] == access_control(PLAN)
        assert x["transport"]["link"]["protocols"] == ["tls"]
        tls = x["transport"]["link"]["tls"]
        assert tls["enable_mtls"] is True and tls["verify_name_on_connect"] is True
        assert (tls["listen_private_key"], tls["listen_certificate"]) == files_of(r)
    assert Plan(SWARM, 1, ("::1",)).endpoint("::1") == "tls/[::1]:7447"
    on_one_machine = Plan(SWARM, 1, ("127.0.0.2", "127.0.0.3", "localhost"))
    assert [on_one_machine.listen(h) for h in on_one_machine.hosts] == [
        ["tls/127.0.0.2:7447"],
        ["tls/127.0.0.3:7447"],
        ["tls/localhost:7447"],
    ]


def test_a_client_config_holds_only_its_credentials() -> None:
    world = next(w for w in PLAN.identities if w.name == "world")
    conf = part_config(PLAN, world)
    assert conf["mode"] == "client" and "access_control" not in conf
    assert "connect" not in conf and "listen" not in conf
    assert conf["transport"]["link"]["tls"] == {
        "root_ca_certificate": "ca.pem",
        "enable_mtls": True,
        "verify_name_on_connect": True,
        "connect_private_key": "world.key",
        "connect_certificate": "world.pem",
    }
    text = config_text(PLAN, world)
    assert text.startswith("// fatswarm secure: swarm 'lab', identity 'world'")


# --- the folder --------------------------------------------------------------------------------


def test_the_folder_holds_the_authority_and_every_identity(tmp_path: Path) -> None:
    from cryptography import x509
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    plan = Plan(SWARM, 2, ("127.0.0.1", "router.example"), 17447, 1)
    out = tmp_path / "secure"
    written = pki.write_bundle(plan, out)
    names = sorted(p.name for p in written)
    expected = ["README.txt", "ca.pem"]
    for who in plan.identities:
        expected += [*files_of(who), config_name(who)]
    assert names == sorted(expected) and sorted(os.listdir(out)) == names
    assert stat.S_IMODE(out.stat().st_mode) == 0o700
    ca = x509.load_pem_x509_certificate((out / "ca.pem").read_bytes())
    assert not list(out.glob("ca.key")) and not list(out.glob("ca*.key"))  # never kept
    for who in plan.identities:
        key_file, cert_file = files_of(who)
        assert stat.S_IMODE((out / key_file).stat().st_mode) == 0o600
        cert = x509.load_pem_x509_certificate((out / cert_file).read_bytes())
        cert.verify_directly_issued_by(ca)
        assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == who.name
        usages = cert.extensions.get_extension_for_class(x509.ExtendedKeyUsage).value
        assert ExtendedKeyUsageOID.CLIENT_AUTH in usages
        assert (ExtendedKeyUsageOID.SERVER_AUTH in usages) == (who.role == "router")
        alt = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
        if who.host == "127.0.0.1":
            assert [str(ip) for ip in alt.get_values_for_type(x509.IPAddress)] == ["127.0.0.1"]
        if who.host == "router.example":
            assert alt.get_values_for_type(x509.DNSName) == ["router.example", "localhost"]
            assert [str(ip) for ip in alt.get_values_for_type(x509.IPAddress)] == ["127.0.0.1"]
        now = datetime.datetime.now(datetime.UTC)
        assert cert.not_valid_before_utc < now < cert.not_valid_after_utc
        conf = load_config_file(str(out / config_name(who)))  # Zenoh reads it; paths resolve
        assert json.loads(conf.get_json("transport/link/tls/connect_certificate")) == str(
            out / cert_file
        )


def test_an_existing_folder_is_kept_unless_force(tmp_path: Path) -> None:
    plan = Plan(SWARM, 1, ("127.0.0.1",))
    out = tmp_path / "secure"
    out.mkdir()
    (out / "precious").write_text("keep")
    with pytest.raises(FileExistsError, match="--force"):
        pki.write_bundle(plan, out)
    assert (out / "precious").read_text() == "keep"
    pki.write_bundle(plan, out, force=True)
    assert not (out / "precious").exists() and (out / "world.pem").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["secure"]  # no temporary folder left


def _secure(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = cli.main(["secure", *argv])
    captured = capsys.readouterr()
    assert captured.out == ""
    return code, captured.err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--swarm", "a b", "-n", "2"], "swarm name must be"),
        (["--swarm", "lab", "-n", "0"], "-n must be in 1..4096"),
        (["--swarm", "lab", "-n", "x"], "invalid int value"),
        (["--swarm", "lab", "-n", "2", "--hosts", "10.0.0.1,,10.0.0.2"], "an empty entry"),
        (["--swarm", "lab", "-n", "2", "--hosts", "0.0.0.0"], "a wildcard address"),
        (["--swarm", "lab", "-n", "2", "--days", "0"], "--days must be at least 1"),
        (["--swarm", "lab", "-n", "2", "--port", "70000"], "--port must be in 1..65535"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, argv: list[str], said: str
) -> None:
    code, err = _secure(capsys, *argv, "--out", str(tmp_path / "out"))
    assert code == ExitCode.BAD_INPUT
    assert err.startswith("fatswarm secure: ") and err.count("\n") == 1 and said in err, err
    assert not (tmp_path / "out").exists()


def test_the_command_refuses_an_existing_folder_or_a_missing_parent(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    (tmp_path / "out").mkdir()
    code, err = _secure(capsys, "--swarm", "lab", "-n", "2", "--out", str(tmp_path / "out"))
    assert (
        code == 2
        and err
        == f"fatswarm secure: {tmp_path / 'out'} exists: pick another "
        "--out, or --force to replace it\n"
    )
    code, err = _secure(capsys, "--swarm", "lab", "-n", "2", "--out", str(tmp_path / "no/out"))
    assert code == 2 and "does not exist" in err and err.count("\n") == 1
    code, err = _secure(
        capsys,
        "--swarm",
        "lab",
        "-n",
        "2",
        "--out",
        str(tmp_path / "out"),
        "--force",
        "--hosts",
        "10.0.0.1",
        "--hosts",
        "10.0.0.2,h.example",
    )
    assert code == 0 and "wrote 26 files" in err, err  # 8 identities x 3, ca.pem, README
    assert (tmp_path / "out" / "router-h.example.json5").exists()


def test_without_cryptography_the_command_says_what_to_install(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "cryptography", None)  # import fails
    code, err = _secure(capsys, "--swarm", "lab", "-n", "2", "--out", str(tmp_path / "out"))
    assert code == 2
    assert (
        err == "fatswarm secure: certificates need the cryptography package: pip install "
        '"fatswarm[secure]"\n'
    )


def test_the_help_says_what_it_makes(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["secure", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for words in (
        "certificate authority",
        "default deny",
        "only the coordinator may open and commit rounds",
        "--force",
        "--hosts",
    ):
        assert words in out, words


# --- --config ----------------------------------------------------------------------------------


@pytest.fixture
def bundle(tmp_path: Path) -> Path:
    out = tmp_path / "secure"
    pki.write_bundle(Plan(SWARM, 2, ("127.0.0.1",), 17447), out)
    return out


def test_the_parts_settings_go_on_top_of_the_file(bundle: Path) -> None:
    router = str(bundle / "router-127.0.0.1.json5")
    conf = make_config("router", config_file=router)  # the file's endpoints stay
    assert listen_endpoints(conf) == ["tls/127.0.0.1:17447"]  # loopback once
    assert json.loads(conf.get_json("access_control/default_permission")) == "deny"
    conf = make_config("router", listen=["tls/127.0.0.1:1"], config_file=router)
    assert listen_endpoints(conf) == ["tls/127.0.0.1:1"]  # flags replace them
    agent = str(bundle / "agent-0.json5")
    conf = make_config("client", ["tls/127.0.0.1:17447"], config_file=agent, lease_ms=2000)
    assert json.loads(conf.get_json("mode")) == "client"
    assert json.loads(conf.get_json("scouting/multicast/enabled")) is False
    assert json.loads(conf.get_json("transport/link/tx/lease")) == 2000
    assert connect_endpoints(conf) == ["tls/127.0.0.1:17447"]
    assert listen_endpoints(conf) == []  # never Zenoh's default listener
    # a router's own file without endpoints: the default given
    (bundle / "bare.json5").write_text("{}")
    conf = make_config(
        "router", config_file=str(bundle / "bare.json5"), default_listen=["tcp/127.0.0.1:7447"]
    )
    assert listen_endpoints(conf) == ["tcp/127.0.0.1:7447"]


def test_a_relative_certificate_path_is_read_from_the_files_folder(
    bundle: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    conf = load_config_file(os.path.relpath(bundle / "world.json5"))
    assert json.loads(conf.get_json("transport/link/tls/root_ca_certificate")) == str(
        bundle / "ca.pem"
    )


@pytest.mark.parametrize(
    ("content", "name", "said"),
    [
        (None, "missing.json5", "no such file"),
        (
            "{ mode: ",
            "torn.json5",
            "line 1, column 9: expected array, boolean, null, number, object, or string",
        ),
        ('{\n  modez: "client" }', "typo.json5", "line 2, column 3: unknown field `modez`"),
        ("{}", "conf.txt", "Zenoh reads only .json5, .json, .yaml files"),
        (
            '{ transport: { link: { tls: { root_ca_certificate: "nope.pem" } } } }',
            "ca.json5",
            "root_ca_certificate {dir}/nope.pem: no such file",
        ),
        (
            "{ access_control: { enabled: true, rules: [{ id: 'r', messages: ['pub'], flows: "
            "['ingress'], key_exprs: ['a'], permission: 'allow' }] } }",
            "acl.json5",
            "unknown variant `pub`, expected one of `put`",
        ),
    ],
)
def test_a_bad_file_is_one_line(tmp_path: Path, content: str | None, name: str, said: str) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises(ZenohSetupError) as info:
        make_config("client", ["tcp/127.0.0.1:7447"], config_file=str(path))
    message = str(info.value)
    assert message.startswith(f"--config {path}: ") and "\n" not in message, message
    assert said.format(dir=tmp_path) in message and ".rs" not in message, message
    with pytest.raises(ZenohSetupError, match="is a folder"):
        make_config("client", ["tcp/127.0.0.1:7447"], config_file=str(tmp_path))


def test_an_endpoint_the_file_does_not_allow_is_refused(bundle: Path) -> None:
    with pytest.raises(ZenohSetupError) as info:
        make_config("client", ["tcp/127.0.0.1:7447"], config_file=str(bundle / "agent-0.json5"))
    assert str(info.value) == (
        f"endpoint tcp/127.0.0.1:7447 uses a protocol --config "
        f"{bundle / 'agent-0.json5'} does not allow "
        "(transport/link/protocols: tls)"
    )


def test_no_answer_over_tls_may_be_a_refused_certificate() -> None:
    said = unreachable_message(["tls/127.0.0.1:7447"], 5.0)
    assert (
        said.startswith(
            "no Zenoh router answers at tls/127.0.0.1:7447 (tried for 5 s), or it "
            "refused this part's certificate: "
        )
        and "fatswarm secure" in said
    )


def test_an_agents_config_names_its_robot() -> None:
    assert config_for("s/agent-{robot}.json5", 7) == "s/agent-7.json5"
    assert config_for("s/agent.json5", 7) == "s/agent.json5"
    assert config_for(None, 7) is None
    assert config_for("s/agent-{robot}.json5", None) == "s/agent-{robot}.json5"
