# rcservice: the calibration service (FastAPI + SQLite) in a container.
# Not exercised by CI (no Docker engine on the build machines); see docs/service.md.
#
#   docker build -t rcservice .
#   docker run -p 8000:8000 -v rcservice-data:/data rcservice
#   docker logs <container>      # the admin token generated at first start is printed there
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    RCSERVICE_DATABASE_URL=sqlite:////data/rcservice.db

RUN useradd --create-home --uid 10001 rcservice \
    && mkdir /data && chown rcservice:rcservice /data

WORKDIR /app
COPY pyproject.toml README.md alembic.ini ./
COPY rcengine ./rcengine
COPY service ./service
COPY migrations ./migrations
# Editable, as `make run` installs it: the service applies the migrations in /app/migrations.
RUN pip install -e '.[service]'

USER rcservice
VOLUME /data
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/health', timeout=4).status != 200)"]

# The README's start command (`make run`), listening on every interface of the container.
CMD ["rcservice", "serve", "--host", "0.0.0.0", "--port", "8000"]
