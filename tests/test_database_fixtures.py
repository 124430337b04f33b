"""The databases dynia follow's tests write to: a fresh SQLite file and a fresh database on a real PostgreSQL server."""

import datetime

import pytest
import sqlalchemy as sa


@pytest.fixture
def engine(database_url):
    engine = sa.create_engine(database_url)
    yield engine
    engine.dispose()


def results_table(metadata):
    return sa.Table(
        "results",
        metadata,
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("tag", sa.String(64), nullable=False),
        sa.Column("at", sa.DateTime, nullable=False),
        sa.Column("ic", sa.Float),
    )


def test_a_table_written_is_read_back(engine):
    metadata = sa.MetaData()
    results = results_table(metadata)
    metadata.create_all(engine)
    rows = [
        {"tag": "FIC101.PV", "at": datetime.datetime(2024, 5, 1, 12, 0), "ic": 0.25},
        {"tag": "FIC101.PV", "at": datetime.datetime(2024, 5, 1, 12, 1), "ic": None},
        {"tag": "TIC7 ünïcode", "at": datetime.datetime(2024, 5, 1, 12, 2), "ic": 1e-300},
    ]
    with engine.begin() as connection:
        connection.execute(sa.insert(results), rows)
    with engine.connect() as connection:
        read = connection.execute(sa.select(results.c.tag, results.c.at, results.c.ic).order_by(results.c.id))
        assert [row._asdict() for row in read] == rows


def test_a_rolled_back_transaction_leaves_nothing(engine):
    metadata = sa.MetaData()
    results = results_table(metadata)
    metadata.create_all(engine)
    with pytest.raises(RuntimeError), engine.begin() as connection:
        connection.execute(sa.insert(results), {"tag": "a", "at": datetime.datetime(2024, 1, 1)})
        raise RuntimeError("the follower fails mid-write")
    with engine.connect() as connection:
        assert connection.execute(sa.select(sa.func.count()).select_from(results)).scalar_one() == 0


def test_every_test_gets_an_empty_database(engine):
    # The other tests here create `results`; none of it is left for this one, whichever ran first.
    assert sa.inspect(engine).get_table_names() == []
    metadata = sa.MetaData()
    results_table(metadata)
    metadata.create_all(engine)
    assert sa.inspect(engine).get_table_names() == ["results"]


def test_the_postgres_url_is_a_real_postgresql_server(postgres_url):
    engine = sa.create_engine(postgres_url)
    try:
        with engine.connect() as connection:
            version = connection.execute(sa.text("select version()")).scalar_one()
    finally:
        engine.dispose()
    assert engine.dialect.name == "postgresql"
    assert version.startswith("PostgreSQL "), version


def test_the_database_url_names_its_backend(database_url, request):
    backend = request.node.callspec.params["database_url"]
    assert sa.make_url(database_url).get_backend_name() == backend
