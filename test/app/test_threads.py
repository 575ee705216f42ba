# Copyright 2026 frf_ident developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""One BLAS thread while a forking command runs, in numpy's and in scipy's OpenBLAS alike."""
import os
import subprocess
import sys


def test_one_blas_thread_holds_a_library_first_used_inside_the_block():
    # a fresh interpreter with the libraries' own default thread count, scipy.linalg first
    # imported inside the block, as the diagnosis does
    code = """
from threadpoolctl import threadpool_info
from frf_ident.app.threads import one_blas_thread
with one_blas_thread():
    import scipy.linalg
    inside = [i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas']
after = [i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas']
print(inside, after)
"""
    env = {k: v for k, v in os.environ.items()
           if k not in ('OPENBLAS_NUM_THREADS', 'OMP_NUM_THREADS', 'MKL_NUM_THREADS')}
    inside, after = subprocess.run([sys.executable, '-c', code], capture_output=True,
                                   text=True, env=env, check=True).stdout.split('] ')
    # numpy's and scipy's wheels each bring an OpenBLAS: both held to one thread, and given
    # back their own count afterwards
    assert inside.strip('[') and set(inside.strip('[').split(', ')) == {'1'}
    assert len(after.strip('[]\n').split(', ')) == len(inside.strip('[').split(', '))
    if (os.cpu_count() or 1) > 1:
        assert set(after.strip('[]\n').split(', ')) != {'1'}
