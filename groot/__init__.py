"""Groot2 interoperability: node models for the editor, a live monitor server, .btlog recording.

    from groot import GrootServer, BTLogger, models_xml, embed_models
"""

from .btlog import BTLogger
from .models import embed_models, models_xml
from .server import DEFAULT_PORT, GrootServer

__all__ = ["BTLogger", "DEFAULT_PORT", "GrootServer", "embed_models", "models_xml"]
