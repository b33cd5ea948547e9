# A Dask worker image with tooltransfer installed, built from this repository (docs/cluster.md):
#
#   docker build -t tooltransfer-worker .
#   docker run --rm --network host tooltransfer-worker dask scheduler                     # one machine
#   docker run --rm --network host tooltransfer-worker dask worker tcp://HEAD:8786 --nthreads 4
#   tooltransfer batch run BATCH.yaml --db results.sqlite --scheduler tcp://HEAD:8786    # where the dataset is
#
# No dataset in the image: `batch run` learns the skills where it runs and ships them to the workers.
# The submitting machine needs the same Python minor version (3.11) and the same dask and distributed
# versions as the image (`docker run --rm tooltransfer-worker pip freeze` lists them).

# build stage: the wheel, with the compiled dual active-set core (dmp/qp/_gi_core.c, one abi3 library)
FROM python:3.11-slim AS build
RUN apt-get update \
    && apt-get install -y --no-install-recommends gcc libc6-dev \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY . .
RUN pip wheel --no-cache-dir --no-deps --wheel-dir /wheels .

# run stage: the wheel and its dependencies (PyPI wheels), no compiler
FROM python:3.11-slim
ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    OPENBLAS_NUM_THREADS=1 \
    TOOLTRANSFER_CACHE=/tmp/tooltransfer-cache
COPY --from=build /wheels /wheels
# bokeh: the scheduler's and the workers' dashboards (optional for the batch)
RUN pip install --no-cache-dir "$(ls /wheels/*.whl)[sim,dask]" "bokeh>=3.1" \
    && rm -rf /wheels \
    && python -c "import tooltransfer.planner.apps.batch.execute, tooltransfer.planner.planning.solve, tooltransfer.planner.execution.closed_loop, tooltransfer.planner.execution.simulate; \
from tooltransfer.dmp.qp.native import compiled_path; assert compiled_path(), 'the compiled core was not built'"
# `dask-worker` and `dask-scheduler`: the commands dask's Kubernetes operator starts its pods with
RUN printf '#!/bin/sh\nexec dask worker "$@"\n' > /usr/local/bin/dask-worker \
    && printf '#!/bin/sh\nexec dask scheduler "$@"\n' > /usr/local/bin/dask-scheduler \
    && chmod 755 /usr/local/bin/dask-worker /usr/local/bin/dask-scheduler \
    && useradd --create-home --uid 1000 tooltransfer
USER tooltransfer
WORKDIR /home/tooltransfer
EXPOSE 8786 8787
# the scheduler's address as an argument or in DASK_SCHEDULER_ADDRESS (as the operator sets it)
CMD ["dask", "worker"]
