"""The API's routers, composed by :func:`server.main.create_app`."""
